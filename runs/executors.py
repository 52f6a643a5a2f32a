"""Where simulations run: in-process, local worker processes or a Dask cluster, behind one interface.

Every executor offers :meth:`SampleExecutor.map_unordered`, an iterator of results in completion order.  At
most :attr:`SampleExecutor.max_in_flight` items (``workers`` plus an optional ``prefetch``, default 0) are
outstanding at any time, and the next item is only submitted once the consumer has taken a result (and, in
:mod:`runs.sampling`, committed it to the store).  So a run killed at any moment has lost at most
``max_in_flight`` computations, and workers never race far ahead of what is saved.  ``prefetch`` trades that
bound for throughput: each worker then has its next item queued while its result travels back (5–10 % more
throughput for 10 ms simulations on 2 local processes).

Use :func:`make_executor` to get one::

    make_executor()                             # all cores, local processes
    make_executor(workers=1)                    # in-process, no pool (tests, debugging, profiling)
    make_executor(scheduler="tcp://head:8786")  # a Dask cluster (pip install 'mechopt[dask]')
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import socket
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from itertools import islice
from typing import Any, TypeVar
from urllib.parse import urlsplit

from mechopt.errors import InputError, StudyError
from mechopt.runs.clean_termination import SigtermAsExit, Terminated
from mechopt.runs.main_guard import check_main_guard, leave_quietly_if_bootstrapping
from mechopt.runs.worker_processes import mp_context as _mp_context
from mechopt.runs.worker_processes import start_worker as _start_worker
from mechopt.runs.worker_processes import warm_up as _warm_up

__all__ = [
    "DaskExecutor",
    "InProcessExecutor",
    "ProcessExecutor",
    "SampleExecutor",
    "check_reachable",
    "default_workers",
    "make_executor",
]

T = TypeVar("T")
R = TypeVar("R")

DASK_MISSING = "Dask is not installed: install the dask extra: pip install 'mechopt[dask]'"


def default_workers() -> int:
    """Number of cores this process may use.

    Returns
    -------
    int
        The CPU affinity count where the OS reports it (containers and ``taskset`` restrict it below
        ``os.cpu_count()``), otherwise ``os.cpu_count()``; at least 1.
    """
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


class SampleExecutor(ABC):
    """Runs a function over items in parallel and yields the results as they complete.

    Attributes
    ----------
    workers : int
        Number of items run at the same time.
    max_in_flight : int
        Most items submitted but not yet taken by the consumer: ``workers + prefetch``.
    description : str
        Human-readable summary for logs and reports, e.g. ``"2 local processes"``.
    """

    workers: int
    max_in_flight: int
    description: str

    @abstractmethod
    def map_unordered(self, fn: Callable[[T], R], items: Iterable[T]) -> Iterator[R]:
        """Apply ``fn`` to every item and yield the results in completion order.

        Parameters
        ----------
        fn : callable
            A picklable function of one item (a top-level function of an importable module, or a
            ``functools.partial`` of one).  Its exceptions propagate to the consumer.
        items : iterable
            Consumed lazily: an item is submitted only when a slot is free.

        Yields
        ------
        object
            ``fn(item)`` for each item, in completion order.

        Raises
        ------
        StudyError
            If the execution machinery itself failed (a worker process died, a Dask worker was lost).
        """

    def close(self) -> None:  # noqa: B027 - optional hook, not every executor holds resources
        """Release the executor's resources (idempotent)."""

    def __enter__(self) -> SampleExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<{type(self).__name__}: {self.description}>"


class InProcessExecutor(SampleExecutor):
    """Runs every item in the calling process, one after the other: no pool, no pickling.

    Useful for tests, debugging (breakpoints and tracebacks work) and profiling.
    """

    def __init__(self) -> None:
        self.workers = 1
        self.max_in_flight = 1
        self.description = "in-process (1 worker)"

    def map_unordered(self, fn: Callable[[T], R], items: Iterable[T]) -> Iterator[R]:
        """Yield ``fn(item)`` for each item in order (see :meth:`SampleExecutor.map_unordered`)."""
        for item in items:
            yield fn(item)


class ProcessExecutor(SampleExecutor):
    """Local worker processes (``concurrent.futures.ProcessPoolExecutor``, forkserver or spawn start).

    Parameters
    ----------
    workers : int
        Number of worker processes (≥ 1).
    prefetch : int, optional
        Items submitted beyond ``workers`` (default 0); see the module docstring.

    Notes
    -----
    Workers import the function by reference, so it must be a top-level function of an importable module (not
    a lambda, a local function or a function defined in an unguarded ``__main__`` script).
    """

    def __init__(self, workers: int, *, prefetch: int = 0) -> None:
        leave_quietly_if_bootstrapping()
        check_main_guard(workers)
        self.workers = workers
        self.max_in_flight = workers + prefetch
        self.description = f"{workers} local process{'es' if workers != 1 else ''}"
        self._pool: ProcessPoolExecutor | None = ProcessPoolExecutor(
            max_workers=workers, mp_context=_mp_context(), initializer=_start_worker
        )
        # Start the workers now, in the background, while the method plans its first designs: on a busy machine a
        # cold start of 8 workers takes seconds, which would otherwise come before the first simulation.
        threading.Thread(target=_warm_up, args=(self._pool, workers), name="mechopt-pool-warm-up", daemon=True).start()
        self._sigterm = SigtermAsExit()

    def map_unordered(self, fn: Callable[[T], R], items: Iterable[T]) -> Iterator[R]:
        """Run ``fn`` over ``items`` in the worker processes (see :meth:`SampleExecutor.map_unordered`).

        Raises
        ------
        InputError
            If ``fn`` cannot be pickled (lambda, local function...).
        StudyError
            If a worker process died (crash in native code, out of memory, killed, or a script without a main guard).
        """
        if self._pool is None:
            raise InputError("the executor is closed")
        try:
            pickle.dumps(fn)
        except Exception as exc:
            # Without this check every task would fail one by one with the same pickling error.
            raise InputError(
                f"the simulator function must be picklable (a top-level function of an importable module) to "
                f"run in worker processes: {_one_line(exc)}"
            ) from exc
        pool = self._pool
        it = iter(items)
        pending: set[Future] = set()
        try:
            pending.update(pool.submit(fn, item) for item in islice(it, self.max_in_flight))
            while pending:
                done, pending = wait(pending, return_when=FIRST_COMPLETED)
                for fut in done:
                    yield fut.result()
                    # Refill only now that the consumer has taken (and saved) the result.
                    pending.update(pool.submit(fn, item) for item in islice(it, 1))
        except BrokenProcessPool as exc:
            # A script that starts workers re-runs its top level in each of them unless guarded: they die at start.
            raise StudyError(
                "a worker process died (crash in native code, out of memory, killed, or a script that runs "
                "workers without `if __name__ == \"__main__\":` around its top level); results so far are saved, "
                "run again to resume"
            ) from exc
        finally:
            for fut in pending:
                fut.cancel()

    def close(self) -> None:
        """Shut the pool down, cancelling what has not started (idempotent)."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
            self._sigterm.restore()

    def __exit__(self, exc_type: type[BaseException] | None, *exc: object) -> None:
        if exc_type is not None and issubclass(exc_type, KeyboardInterrupt | Terminated):
            self._interrupt_workers()
        self.close()

    def _interrupt_workers(self) -> None:
        """Pass an interrupt of the main process alone (a notebook's stop, ``kill -INT``, the SIGTERM of
        :mod:`mechopt.cli.main`) on to the workers, which stop the programs they started (:func:`_quiet_interrupt`):
        the shutdown then waits for no external program."""
        if self._pool is None or os.name != "posix":
            return
        for process in list((getattr(self._pool, "_processes", None) or {}).values()):
            with contextlib.suppress(OSError, TypeError):
                os.kill(process.pid, signal.SIGINT)


def check_reachable(address: str, timeout: float = 10.0) -> None:
    """Fail fast, with one line, when nothing listens at a ``tcp://`` or ``tls://`` scheduler address (``timeout``
    in s); a command calls it before it makes its output folder.

    A ``distributed.Client`` that fails to connect leaves behind an object whose finalizer blocks and prints a
    traceback at exit; a plain socket probe avoids creating it.
    """
    # distributed reads a bare "HOST:PORT" as tcp.
    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    if parts.scheme not in ("tcp", "tls"):
        return  # other transports (inproc, ucx): let distributed judge
    try:
        host, port = parts.hostname, parts.port
    except ValueError as exc:
        raise InputError(f"invalid Dask scheduler address {address}: {_one_line(exc)}") from exc
    if not host or port is None:
        raise InputError(f"invalid Dask scheduler address {address}: expected tcp://HOST:PORT")
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as exc:
        raise InputError(f"cannot reach the Dask scheduler at {address}: {_one_line(exc)}") from exc


class DaskExecutor(SampleExecutor):
    """A Dask distributed cluster.

    Parameters
    ----------
    scheduler : str or distributed.Client or distributed.LocalCluster
        Scheduler address (``"tcp://HOST:PORT"``), an existing client (used, not closed) or a cluster object
        with a ``scheduler_address`` (e.g. a ``LocalCluster``; a client is connected to it and closed at
        exit).
    workers : int, optional
        Items run at once; default: the total number of worker threads of the cluster at start.
    prefetch : int, optional
        Items submitted beyond ``workers`` (default 0); hides the scheduler's round trip on short simulations.
    connect_timeout : float, optional
        Seconds to wait for the scheduler, and for a first worker if it has none (default 10).

    Raises
    ------
    InputError
        If Dask is not installed, the scheduler cannot be reached or it has no worker.

    Notes
    -----
    The workers must be able to import :mod:`studies` (mechopt installed in their environment) and the
    simulator function's module.
    """

    def __init__(
        self, scheduler: Any, workers: int | None = None, *, prefetch: int = 0, connect_timeout: float = 10.0
    ) -> None:
        try:
            import distributed
        except ImportError as exc:
            raise InputError(DASK_MISSING) from exc
        self._distributed = distributed
        if isinstance(scheduler, distributed.Client):
            self._client: Any = scheduler
            self._own_client = False
        else:
            address = getattr(scheduler, "scheduler_address", scheduler)
            if not isinstance(address, str) or not address:
                raise InputError(f"the Dask scheduler must be an address like tcp://HOST:PORT, got {scheduler!r}")
            check_reachable(address, connect_timeout)
            try:
                self._client = distributed.Client(address, timeout=connect_timeout, set_as_default=False)
            except (OSError, TimeoutError, ValueError) as exc:
                raise InputError(f"cannot reach the Dask scheduler at {address}: {_one_line(exc)}") from exc
            self._own_client = True
        try:
            threads = sum(self._client.nthreads().values())
            if threads == 0:
                self._client.wait_for_workers(1, timeout=connect_timeout)
                threads = sum(self._client.nthreads().values())
        except (OSError, TimeoutError) as exc:
            address = self._client.scheduler.address
            self.close()
            raise InputError(f"the Dask scheduler at {address} has no worker: {_one_line(exc)}") from exc
        self.workers = workers if workers is not None else max(1, threads)
        self.max_in_flight = self.workers + prefetch
        self.description = f"Dask at {self._client.scheduler.address} ({threads} worker threads)"

    def map_unordered(self, fn: Callable[[T], R], items: Iterable[T]) -> Iterator[R]:
        """Run ``fn`` over ``items`` on the cluster (see :meth:`SampleExecutor.map_unordered`).

        Raises
        ------
        InputError
            If the executor was closed.
        StudyError
            If the cluster lost a task (``KilledWorker``: a worker died while running it, repeatedly).
        """
        if self._client is None:
            raise InputError("the executor is closed")
        client = self._client
        killed_worker = self._distributed.KilledWorker
        it = iter(items)

        def submit(item: T) -> Any:
            # pure=False: every call is a fresh task, never merged with another by key.
            return client.submit(fn, item, pure=False)

        pending = {submit(item) for item in islice(it, self.max_in_flight)}
        queue = self._distributed.as_completed(list(pending), loop=client.loop)
        try:
            for fut in queue:
                pending.discard(fut)
                try:
                    result = fut.result()
                except killed_worker as exc:
                    raise StudyError(
                        f"the Dask cluster lost a task ({_one_line(exc)}); results so far are saved, "
                        "run again to resume"
                    ) from exc
                finally:
                    fut.release()
                yield result
                for item in islice(it, 1):
                    new = submit(item)
                    pending.add(new)
                    queue.add(new)
        finally:
            if pending:
                client.cancel(list(pending))

    def close(self) -> None:
        """Close the client if this executor opened it (idempotent)."""
        if self._client is not None and self._own_client:
            self._client.close()
        self._client = None


def make_executor(
    workers: int | None = None, scheduler: Any = None, *, prefetch: int = 0, connect_timeout: float = 10.0
) -> SampleExecutor:
    """The executor for a sampling run.

    Parameters
    ----------
    workers : int, optional
        Local processes (default: every core, :func:`default_workers`); ``1`` runs in-process without a pool.
        With ``scheduler``, the designs run at once (default: the cluster's worker threads).
    scheduler : str or distributed.Client or distributed.LocalCluster, optional
        Run on a Dask distributed cluster instead: a scheduler address ``"tcp://HOST:PORT"``, an existing
        client or a ``LocalCluster``.
    prefetch : int, optional
        Designs submitted beyond ``workers`` (default 0): a little more throughput on short simulations, at
        the price of up to ``workers + prefetch`` (instead of ``workers``) results lost if the run is killed.
        Ignored in-process.
    connect_timeout : float, optional
        Seconds to wait for the Dask scheduler (default 10).

    Returns
    -------
    SampleExecutor
        Use it as a context manager so that its pool or client is released.

    Raises
    ------
    InputError
        If ``workers`` is not a positive integer, ``prefetch`` not a non-negative one, Dask is not installed,
        or the scheduler cannot be reached.
    """
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise InputError(f"workers must be a positive integer, got {workers!r}")
    if isinstance(prefetch, bool) or not isinstance(prefetch, int) or prefetch < 0:
        raise InputError(f"prefetch must be a non-negative integer, got {prefetch!r}")
    if scheduler is not None:
        return DaskExecutor(scheduler, workers, prefetch=prefetch, connect_timeout=connect_timeout)
    n = default_workers() if workers is None else workers
    return InProcessExecutor() if n == 1 else ProcessExecutor(n, prefetch=prefetch)
