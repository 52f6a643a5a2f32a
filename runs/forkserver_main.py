"""Preloaded by the fork server of the local worker processes: the main script imported once there, not per worker.

Every worker process of :class:`~mechopt.runs.executors.ProcessExecutor` must import the parent's main script (a
simulator function defined in it is pickled by reference).  The fork server is meant to import it once and fork every
worker from that, but CPython 3.11 never hands it the script's path (``ForkServer.ensure_running`` keeps the keys
``main_path`` and ``sys_path`` of preparation data that names it ``init_main_from_path``), so each worker imported it
anew: with a script that imports mechopt's optimizers, 1.5 s of CPU per worker, 14 s before the first simulation on 8
workers on 2 cores.  The parent puts the script's path (or module name) in an environment variable before
the server starts (:func:`mechopt.runs.worker_processes.mp_context`); importing this module in the server imports it, as
the server would with the path, and each worker forked from there finds it already loaded.
"""

from __future__ import annotations

import os

#: The environment variable that names the parent's main script: ``path:FILE`` or ``name:MODULE``.
MAIN_VARIABLE = "MECHOPT_FORKSERVER_MAIN"


def _import_main() -> None:
    """Import the parent's main script as ``__mp_main__`` (and ``__main__``), as the fork server should."""
    from multiprocessing import process, spawn

    value = os.environ.pop(MAIN_VARIABLE, "")
    kind, _, target = value.partition(":")
    if not target:
        return
    process.current_process()._inheriting = True  # as CPython does: a script's unguarded Process() raises
    try:
        if kind == "path":
            spawn.import_main_path(target)
        elif kind == "name":
            spawn._fixup_main_from_name(target)
    except Exception:  # noqa: BLE001 - the workers then import it themselves and report what fails
        pass
    finally:
        del process.current_process()._inheriting


if os.environ.get(MAIN_VARIABLE):
    _import_main()
