"""The main-guard mistake of a script that starts worker processes, told in one line before any worker starts.

Local worker processes start by forkserver or spawn (never fork: the parent holds threads and an SQLite connection),
and each imports the main script again to find the simulator's code.  A script whose top level calls
``minimize(..., workers=2)`` without ``if __name__ == "__main__":`` would run that call again in every worker, which
fails there: each worker printed its traceback, the pool broke, and the one line that explains it came last, after
some hundred lines.  :func:`check_main_guard` reads the main script before the pool is made and ends the script with
that one line (:class:`MainGuardExit`, a ``SystemExit``: the script's own top level could not go on anyway, and
Python prints a ``SystemExit``'s message alone, without a traceback); :func:`leave_quietly_if_bootstrapping` makes
a worker that still gets there (a guard this check cannot read, ``exec``'d code) leave without a traceback, for the
parent to explain.
"""

from __future__ import annotations

import ast
import multiprocessing
import os
import sys
from types import FrameType

__all__ = ["MainGuardExit", "check_main_guard", "leave_quietly_if_bootstrapping", "unguarded_line"]


class MainGuardExit(SystemExit):
    """Worker processes started from the unguarded top level of the main script: the script ends with one line."""


def _is_main_test(test: ast.expr) -> bool:
    """``__name__ == "__main__"`` (either way round)."""
    if not (isinstance(test, ast.Compare) and len(test.ops) == 1 and isinstance(test.ops[0], ast.Eq)):
        return False
    sides = {test.left.__class__, test.comparators[0].__class__}
    names = [s.id for s in (test.left, test.comparators[0]) if isinstance(s, ast.Name)]
    values = [s.value for s in (test.left, test.comparators[0]) if isinstance(s, ast.Constant)]
    return sides == {ast.Name, ast.Constant} and names == ["__name__"] and values == ["__main__"]


def _guarded_lines(source: str) -> list[tuple[int, int]]:
    """(first, last) line of the body of each top-level ``if __name__ == "__main__":`` block."""
    tree = ast.parse(source)
    return [(node.body[0].lineno, node.end_lineno or node.body[-1].lineno) for node in tree.body
            if isinstance(node, ast.If) and _is_main_test(node.test)]


def _main_frame() -> tuple[str, int] | None:
    """File and line of the main script's top-level code in the current call stack, if it is running there."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if main is None or not path:
        return None
    frame: FrameType | None = sys._getframe(1)
    while frame is not None:
        if frame.f_globals is vars(main) and frame.f_code.co_name == "<module>":
            return str(path), frame.f_lineno
        frame = frame.f_back
    return None


def unguarded_line() -> tuple[str, int] | None:
    """The main script and the line of its top level, outside a main guard, that led to this call; None if none."""
    where = _main_frame()
    if where is None:
        return None
    path, line = where
    try:
        with open(path, encoding="utf-8") as fh:
            blocks = _guarded_lines(fh.read())
    except (OSError, SyntaxError, ValueError):
        return None  # not readable as Python source: the worker's quiet exit and the parent's line still explain
    return None if any(first <= line <= last for first, last in blocks) else (path, line)


def check_main_guard(workers: int) -> None:
    """Refuse, in one line, worker processes started from the unguarded top level of the main script.

    Parameters
    ----------
    workers : int
        The worker processes about to start (named in the message).

    Raises
    ------
    MainGuardExit
        When the main script's top level, outside ``if __name__ == "__main__":``, led to this call; its message
        (``"mechopt: error: ..."``, one line) is what Python prints as the script ends, with exit status 1.
    """
    where = unguarded_line()
    if where is None:
        return
    path, line = where
    raise MainGuardExit(f"mechopt: error: workers = {workers} start processes that import the main script "
                        f"{os.path.basename(path)} again, and its line {line} would run there too: put the script's "
                        'top-level code under `if __name__ == "__main__":` (or use workers=1)')


def leave_quietly_if_bootstrapping() -> None:
    """In a worker process still importing the main script (its unguarded top level starting workers), exit at once
    and silently: the parent sees the worker gone and says why in one line."""
    if getattr(multiprocessing.current_process(), "_inheriting", False):
        os._exit(1)
