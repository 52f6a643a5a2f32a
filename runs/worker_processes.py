"""The worker processes of :class:`~mechopt.runs.executors.ProcessExecutor`: how they are started (forkserver with
mechopt preloaded), what each does first (leave with the parent, take Ctrl-C quietly), and how a pool is warmed up.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import threading
import time
from concurrent.futures import ProcessPoolExecutor, wait
from pathlib import Path

from mechopt.runs.forkserver_main import MAIN_VARIABLE

__all__ = ["die_with_parent", "kill_programs", "main_for_forkserver", "mp_context", "pause", "quiet_interrupt",
           "start_worker", "warm_up"]


def start_worker() -> None:
    """Pool-worker initializer: leave with the parent, and quietly on Ctrl-C."""
    die_with_parent()
    quiet_interrupt()


def quiet_interrupt() -> None:
    """Leave SIGINT to the main process; on a Ctrl-C only stop the programs this worker started.

    A Ctrl-C in a terminal reaches the whole foreground process group: every worker as well as the main process.
    Python's default turned it into a KeyboardInterrupt in each worker, and each printed its traceback (pymunk's
    callbacks theirs too) under the main process's one line; a worker that left at once, or that the main process
    terminated, left the pool's semaphores behind and Python warned of them.  So a worker ignores it: a Python
    simulation in progress ends in milliseconds to seconds, and the main process, which alone writes the store,
    drops its result.  An external program (a command simulator runs each in a session of its own, out of the
    terminal's reach) may run for minutes: its process group is killed, so the user does not wait for a result
    nobody will store.
    """
    signal.signal(signal.SIGINT, lambda _signum, _frame: kill_programs())


def kill_programs() -> None:
    """SIGKILL the process group of every child process of this process (Linux; elsewhere nothing)."""
    for children in Path("/proc/self/task").glob("*/children"):
        try:
            pids = [int(pid) for pid in children.read_text().split()]
        except (OSError, ValueError):
            continue
        for pid in pids:
            with contextlib.suppress(OSError):
                if os.getpgid(pid) == pid:
                    os.killpg(pid, signal.SIGKILL)
                else:
                    os.kill(pid, signal.SIGKILL)


def die_with_parent() -> None:
    """Exit as soon as the parent process is gone.

    A ``ProcessPoolExecutor`` worker whose parent was SIGKILLed would otherwise block forever on its task
    queue (or keep burning a core), so a killed run would leave orphans behind.
    """
    parent = multiprocessing.parent_process()
    if parent is None:
        return

    def watch() -> None:
        parent.join()  # returns when the parent's sentinel pipe closes, i.e. when the parent died
        os._exit(1)

    threading.Thread(target=watch, name="mechopt-parent-watch", daemon=True).start()


def mp_context() -> multiprocessing.context.BaseContext:
    """The start method of the worker processes: forkserver with mechopt preloaded where there is one, else spawn."""
    # Not "fork": the parent may hold threads (tqdm monitor, a Dask client) and an SQLite connection, neither
    # of which survives fork() safely.  forkserver is the Python 3.14 default on POSIX; spawn elsewhere.
    methods = multiprocessing.get_all_start_methods()
    if "forkserver" not in methods:
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    # The server imports mechopt (numpy, scipy...) once and forks every worker from it, instead of each worker
    # importing it anew (seconds per worker).  Only the first start of the server reads this list.  The main
    # script goes through mechopt.runs.forkserver_main: the server's own preload of "__main__" never gets its path.
    main = main_for_forkserver()
    if main:
        os.environ.setdefault(MAIN_VARIABLE, main)
    context.set_forkserver_preload(["__main__", "mechopt.runs.forkserver_main", "mechopt.runs.sampling"])
    return context


def main_for_forkserver() -> str:
    """``path:FILE`` or ``name:MODULE`` of the main script, as the workers would import it; "" for none."""
    from multiprocessing import spawn

    data = spawn.get_preparation_data("mechopt-worker")
    if data.get("init_main_from_name"):
        return f"name:{data['init_main_from_name']}"
    if data.get("init_main_from_path"):
        return f"path:{data['init_main_from_path']}"
    return ""


def pause(seconds: float) -> None:
    """A task that only takes a worker for a moment: each warm-up task then starts a worker of its own."""
    time.sleep(seconds)


def warm_up(pool: ProcessPoolExecutor, workers: int) -> None:
    """Start every worker of ``pool`` (a pool starts one per submitted task while none is idle)."""
    try:
        wait([pool.submit(pause, 0.05) for _ in range(workers)])
    except Exception:  # noqa: BLE001 - closed or broken meanwhile: the first real task reports it
        pass
