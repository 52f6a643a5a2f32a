"""A SIGTERM to a script with local worker processes ends it cleanly: pool shut down, no leaked semaphores.

Python's default SIGTERM ends the process at once; the pool's queues and locks are never released and
multiprocessing's resource tracker warns of "leaked semaphore objects" at shutdown.  While a process pool is open,
:class:`SigtermAsExit` turns a SIGTERM of the main thread into :class:`Terminated` (a ``SystemExit`` with the
shell's status 143 = 128 + SIGTERM, which Python prints nothing for), so the executor shuts its pool down on the
way out.  It only replaces the default disposition: a program that handles SIGTERM itself (``mechopt``'s command
line does) keeps its own handler.
"""

from __future__ import annotations

import signal
import threading
from types import FrameType

__all__ = ["SigtermAsExit", "Terminated"]

_SIGTERM_STATUS = 128 + int(signal.SIGTERM)


class Terminated(SystemExit):
    """A SIGTERM received while worker processes were running."""


def _raise_terminated(_signum: int, _frame: FrameType | None) -> None:
    raise Terminated(_SIGTERM_STATUS)


class SigtermAsExit:
    """Raise :class:`Terminated` on SIGTERM until :meth:`restore` (only where SIGTERM had its default action)."""

    def __init__(self) -> None:
        self._installed = False
        if threading.current_thread() is not threading.main_thread():
            return  # signal handlers belong to the main thread
        try:
            if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
                signal.signal(signal.SIGTERM, _raise_terminated)
                self._installed = True
        except (ValueError, OSError):  # an embedded interpreter without signals
            pass

    def restore(self) -> None:
        """Put the default action back (idempotent)."""
        if self._installed and threading.current_thread() is threading.main_thread():
            if signal.getsignal(signal.SIGTERM) is _raise_terminated:
                signal.signal(signal.SIGTERM, signal.SIG_DFL)
            self._installed = False
