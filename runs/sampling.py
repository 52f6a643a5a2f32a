"""Evaluate many designs in parallel, resumably and cooperatively: stored results are reused, the rest computed.

:func:`sample_designs` is the single entry point.  The problem is a :class:`~mechopt.optimize.problem.DesignProblem`
whose ``evaluate(x)`` returns a dict with at least every name of ``problem.outputs`` as finite numbers; it may raise
:class:`~mechopt.errors.InfeasibleDesignError` (recorded as ``infeasible``) or anything else (recorded as ``failed``
with a one-line message).  Neither stops the run.

Only the calling process writes to the store, one committed transaction per result, as results arrive.  Together
with the executors' bounded submission this means a run killed at any time loses at most ``executor.max_in_flight``
evaluations and never evaluates a stored design again.

Runs sharing a store share the work.  A run claims a few designs at a time (as many as its executor has free slots)
before evaluating them, with a lease that a heartbeat thread renews every ``lease_s / 3``; designs validly claimed by
another run are not evaluated but waited for, and taken over when their claim expires (their run died) or is
released (it was interrupted).  Claims are released when the call ends, however it ends.
"""

from __future__ import annotations

import functools
import json
import math
import threading
import time
from collections import deque
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from mechopt.errors import InfeasibleDesignError, InputError, MechoptError
from mechopt.optimize.problem import DesignProblem
from mechopt.runs.executors import SampleExecutor, make_executor
from mechopt.runs.store import SampleRecord, SampleStore, as_design, design_key, new_owner, utc_timestamp

__all__ = ["SamplingResult", "evaluate_one", "sample_designs"]

# Long enough for any useful message, short enough for a table cell or a log line.
_MAX_ERROR_CHARS = 500

# Polling of designs another run is evaluating: first check soon (short evaluations), then back off.
_POLL_FIRST_S = 0.02
_POLL_MAX_S = 0.5


@dataclass(frozen=True)
class SamplingResult:
    """Outcome of :func:`sample_designs`.

    Attributes
    ----------
    records : list of SampleRecord
        One record per requested design, in the order of the request (a design requested twice, or twice up to
        float noise, appears twice, as the same record).
    n_requested : int
        Number of designs requested, duplicates included.
    n_unique : int
        Number of distinct designs (by :func:`~mechopt.runs.store.design_key`).
    n_cached : int
        Distinct designs found in the store at the start, not evaluated again.
    n_computed : int
        Distinct designs evaluated by this call.
    n_failed, n_infeasible : int
        Distinct designs whose record (cached or new) is ``failed`` / ``infeasible``.
    n_waited : int
        Distinct designs another run was evaluating: this call waited for their results instead of evaluating
        them (``n_cached + n_computed + n_waited == n_unique``).
    wall_time_s : float
        Wall time of the whole call, s.
    compute_time_s : float
        Sum of the evaluator wall times of the designs evaluated by this call, s (the serial cost; divided by
        ``wall_time_s`` it gives the achieved parallel speed-up).
    executor : str
        Description of the executor used (empty when this call evaluated nothing).
    """

    records: list[SampleRecord]
    n_requested: int
    n_unique: int
    n_cached: int
    n_computed: int
    n_failed: int
    n_infeasible: int
    n_waited: int
    wall_time_s: float
    compute_time_s: float
    executor: str

    @property
    def n_ok(self) -> int:
        """Distinct designs evaluated successfully (cached or new)."""
        return self.n_unique - self.n_failed - self.n_infeasible

    def summary(self) -> dict[str, Any]:
        """The counts and timings as a JSON-able dict (for ``result.json``).

        Returns
        -------
        dict
        """
        return {
            "n_requested": self.n_requested,
            "n_unique": self.n_unique,
            "n_cached": self.n_cached,
            "n_computed": self.n_computed,
            "n_waited": self.n_waited,
            "n_ok": self.n_ok,
            "n_failed": self.n_failed,
            "n_infeasible": self.n_infeasible,
            "wall_time_s": self.wall_time_s,
            "compute_time_s": self.compute_time_s,
            "executor": self.executor,
        }


def _one_line(text: str) -> str:
    text = " ".join(text.split())
    return text if len(text) <= _MAX_ERROR_CHARS else text[: _MAX_ERROR_CHARS - 1] + "…"


def _error_line(exc: BaseException) -> str:
    message = _one_line(str(exc))
    return _one_line(f"{type(exc).__name__}: {message}" if message else type(exc).__name__)


def _jsonable(value: Any) -> Any:
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON-serializable")


class _BadOutputs(Exception):
    """What ``evaluate`` returned cannot be stored; the message names the offending key."""


def _checked_outputs(out: Any, names: Sequence[str]) -> dict[str, Any]:
    """The outputs to store: declared ones as finite floats first, then the extras round-tripped through JSON."""
    if not isinstance(out, Mapping):
        raise _BadOutputs(f"evaluate returned {type(out).__name__}, expected a dict with outputs {list(names)}")
    for k in out:
        if not isinstance(k, str):
            raise _BadOutputs(f"evaluate returned a non-string key {k!r}")
    outputs: dict[str, Any] = {}
    for name in names:
        if name not in out:
            raise _BadOutputs(f"evaluate returned no output {name!r} (got {sorted(out)})")
        value = out[name]
        try:
            if isinstance(value, bool | np.bool_) or np.ndim(value) != 0:
                raise TypeError
            number = float(value)
        except (TypeError, ValueError):
            raise _BadOutputs(f"output {name!r} is not a number: {value!r:.60}") from None
        if not math.isfinite(number):
            raise _BadOutputs(f"output {name!r} is not finite: {number!r}")
        outputs[name] = number
    for k, value in out.items():
        if k in outputs:
            continue
        # Round trip through JSON here, in the worker: what is stored is exactly what the caller gets back, and a
        # non-serializable value fails this design instead of the parent's write.
        try:
            outputs[k] = json.loads(json.dumps(value, default=_jsonable))
        except (TypeError, ValueError) as exc:
            raise _BadOutputs(f"output {k!r} is not JSON-serializable: {exc}") from None
    return outputs


def evaluate_one(problem: DesignProblem, fingerprint: str, design: tuple[float, ...]) -> SampleRecord:
    """Evaluate one design and turn whatever happens into a record (runs in the worker).

    Parameters
    ----------
    problem : DesignProblem
        Its ``evaluate(x)`` is called with ``x = np.asarray(design, float)``.
    fingerprint : str
        Fingerprint to stamp on the record.
    design : tuple of float
        The design, in the variables' units.

    Returns
    -------
    SampleRecord
        ``ok`` with every returned key in ``outputs`` (declared outputs as floats, extras as JSON values);
        ``infeasible`` if ``evaluate`` raised :class:`~mechopt.errors.InfeasibleDesignError`; ``failed`` with the
        one-line ``"ExceptionType: message"`` of any other exception, or a message naming the key of an unusable
        return value (not a dict, a declared output missing, not a number or not finite, an extra not
        JSON-serializable).  Never raises ``Exception``.
    """
    base = {"design": tuple(float(v) for v in design), "fingerprint": fingerprint}
    start = time.perf_counter()
    try:
        out = problem.evaluate(np.asarray(design, dtype=float))
    except InfeasibleDesignError as exc:
        return SampleRecord(**base, status="infeasible", error=_one_line(str(exc)) or "infeasible design",
                            wall_time_s=time.perf_counter() - start)
    except Exception as exc:
        return SampleRecord(**base, status="failed", error=_error_line(exc), wall_time_s=time.perf_counter() - start)
    wall = time.perf_counter() - start
    try:
        outputs = _checked_outputs(out, tuple(problem.outputs))
    except _BadOutputs as exc:
        return SampleRecord(**base, status="failed", error=_one_line(str(exc)), wall_time_s=wall)
    return SampleRecord(**base, status="ok", outputs=outputs, wall_time_s=wall)


class _Heartbeat:
    """Renews a run's claims every ``lease_s / 3`` from a thread with its own connection, while evaluations run."""

    def __init__(self, store: SampleStore, owner: str, lease_s: float) -> None:
        self._args = (store.path, store.timeout, owner, lease_s)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="mechopt-claims-heartbeat", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        path, timeout, owner, lease_s = self._args
        try:
            with SampleStore(path, timeout=timeout) as store:
                while not self._stop.wait(lease_s / 3.0):
                    try:
                        store.renew_claims(owner, lease_s)
                    except MechoptError:
                        pass  # the next beat tries again; a lapse can only make another run duplicate work
        except MechoptError:
            pass

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()


def sample_designs(
    designs: Iterable[Sequence[float]],
    problem: DesignProblem,
    store: SampleStore,
    *,
    fingerprint: str | None = None,
    executor: SampleExecutor | None = None,
    progress: bool = True,
    desc: str = "sampling",
    retry_failed: bool = False,
    lease_s: float = 120.0,
) -> SamplingResult:
    """Evaluate every design not yet in the store, save each result as it arrives, return all records.

    Parameters
    ----------
    designs : iterable of sequences of float
        Designs, each with ``problem.dim`` values in the variables' units.  Duplicates (up to 1e-9) are evaluated
        once.
    problem : DesignProblem
        The problem; must be picklable unless the executor is in-process.
    store : SampleStore
        Where results are looked up and written.
    fingerprint : str, optional
        Key of this problem's rows in the store; default ``problem.fingerprint()``.  Records of other fingerprints
        are neither reused nor touched.
    executor : SampleExecutor, optional
        Where to evaluate; default :func:`~mechopt.runs.executors.make_executor` with every core, created only
        if there is something to evaluate, and closed at the end.  A given executor is left open.
    progress : bool, optional
        Show a tqdm bar with rate, ETA and the cached/waited/failed/infeasible counts (default True; it stays
        silent anyway when stderr is not a terminal).
    desc : str, optional
        Label of the progress bar.
    retry_failed : bool, optional
        Evaluate again the requested designs whose stored record is ``failed`` and replace it (default False:
        failed records are reused like the others).
    lease_s : float, optional
        Lease of this run's claims, s (default 120): how long another run waits before taking over the designs of
        a run that died without releasing them (on the same host it does not wait for a process that is gone).

    Returns
    -------
    SamplingResult
        The records in the order of ``designs``, with counts and timings.

    Raises
    ------
    InputError
        If a design does not have ``problem.dim`` finite values, the problem cannot be sent to the workers, or the
        store cannot be written.
    StudyError
        If the executor itself failed (a worker process died); everything evaluated so far is saved.

    Notes
    -----
    Designs claimed by another live run (one that keeps renewing its claims) are waited for as long as that run
    works on them; its results count in ``n_waited``.  A run that stops (Ctrl-C, an error) releases its claims at
    once; one that is killed leaves them until their lease lapses, or, for a run on the same host, only until the
    next claim attempt.  Two runs whose clocks differ by more than the lease may evaluate a design twice (the first
    stored result is kept), never lose one.
    """
    start = time.perf_counter()
    if retry_failed:
        # Timestamps have millisecond resolution: a failure stored in the same millisecond as this call's start
        # would count as stored since (final), not before (to redo).  One tick later, everything before is earlier.
        time.sleep(0.0011)
    started_at = utc_timestamp()
    if isinstance(lease_s, bool) or not isinstance(lease_s, int | float) or not lease_s > 0:
        raise InputError(f"lease_s must be a positive number of seconds, got {lease_s!r}")
    fp = problem.fingerprint() if fingerprint is None else fingerprint
    dim = len(problem.variables) if getattr(problem, "variables", None) else None
    requested = [as_design(d, dim) for d in designs]
    keys = [design_key(d) for d in requested]
    unique: dict[str, tuple[float, ...]] = {}
    for k, d in zip(keys, requested, strict=True):
        unique.setdefault(k, d)

    def settled(record: SampleRecord) -> bool:
        # With retry_failed, a failure stored before this call is still to be redone; one stored since is final.
        return not (retry_failed and record.status == "failed" and record.timestamp < started_at)

    found = {k: r for k, r in store.get_keys(unique, fp).items() if settled(r)}
    n_cached = len(found)
    pending = {k: d for k, d in unique.items() if k not in found}  # neither stored nor given up
    counts = {"computed": 0, "waited": 0, "failed": 0, "infeasible": 0}
    compute_time = 0.0
    description = ""

    if pending:
        owner = new_owner()
        task = functools.partial(evaluate_one, problem, fp)
        redo = started_at if retry_failed else None
        ex: SampleExecutor | None = executor
        heartbeat: _Heartbeat | None = None
        state = {"claimed": False}
        bar = tqdm(total=len(pending), desc=desc, unit="design", disable=None if progress else True,
                   dynamic_ncols=True)

        def settle(record: SampleRecord, waited: bool) -> None:
            found[record.key] = record
            pending.pop(record.key, None)
            counts["waited" if waited else "computed"] += 1
            if not record.ok:
                counts[record.status] += 1
            shown = {k: v for k, v in counts.items() if v and k != "computed"}
            bar.set_postfix(cached=n_cached, **shown, refresh=False)
            bar.update(1)

        order = list(pending)
        cursor = 0  # order[:cursor] are all settled or submitted

        def claim(submitted: set[str], limit: int) -> list[str]:
            nonlocal cursor
            state["claimed"] = True
            while cursor < len(order) and (order[cursor] not in pending or order[cursor] in submitted):
                cursor += 1
            # Lazy: without contention claim() reads only the first few candidates.
            candidates = (
                order[i] for i in range(cursor, len(order)) if order[i] in pending and order[i] not in submitted
            )
            return store.claim(fp, candidates, owner, lease_s, limit=limit, redo_failed_before=redo)

        def feed(first: list[str], submitted: set[str], limit: int) -> Iterator[tuple[float, ...]]:
            # Pulled by the executor one design per free slot: claim the next few only when the last are submitted,
            # so that at most about max_in_flight designs are claimed but not yet stored.
            queue = deque(first)
            while queue:
                key = queue.popleft()
                submitted.add(key)
                yield pending[key]
                if not queue:
                    queue.extend(claim(submitted, limit))

        bar.set_postfix(cached=n_cached, refresh=False)
        try:
            poll = _POLL_FIRST_S
            while pending:
                # Results of other runs (and of runs that finished meanwhile).
                for record in store.get_keys(pending, fp).values():
                    if settled(record):
                        settle(record, waited=True)
                if not pending:
                    break
                if ex is None:
                    ex = make_executor()
                limit = max(1, ex.max_in_flight)
                submitted: set[str] = set()
                first = claim(submitted, limit)
                if not first:
                    # Everything left is being evaluated by other runs: wait for it, or for a claim to lapse.
                    time.sleep(poll)
                    poll = min(1.5 * poll, _POLL_MAX_S, lease_s / 4.0)
                    continue
                poll = _POLL_FIRST_S
                if heartbeat is None:
                    heartbeat = _Heartbeat(store, owner, lease_s)
                description = ex.description
                for record in ex.map_unordered(task, feed(first, submitted, limit)):
                    if not store.put(record):
                        # Another run stored this design meanwhile (it took over a claim of ours): its row rules.
                        record = store.get_keys([record.key], fp).get(record.key) or record
                    compute_time += record.wall_time_s or 0.0
                    settle(record, waited=False)
        except BaseException:
            _finish(store, owner, state["claimed"], heartbeat, ex if executor is None else None, bar, quiet=True)
            raise
        _finish(store, owner, state["claimed"], heartbeat, ex if executor is None else None, bar, quiet=False)

    statuses = [found[k].status for k in unique]
    return SamplingResult(
        records=[found[k] for k in keys],
        n_requested=len(requested),
        n_unique=len(unique),
        n_cached=n_cached,
        n_computed=counts["computed"],
        n_failed=statuses.count("failed"),
        n_infeasible=statuses.count("infeasible"),
        n_waited=counts["waited"],
        wall_time_s=time.perf_counter() - start,
        compute_time_s=compute_time,
        executor=description,
    )


def _finish(
    store: SampleStore,
    owner: str,
    claimed: bool,
    heartbeat: _Heartbeat | None,
    own_executor: SampleExecutor | None,
    bar: Any,
    quiet: bool,
) -> None:
    """Stop the heartbeat, release this run's claims, close an executor we created, close the bar.

    With ``quiet`` (an exception is on its way out) a failure to release is ignored: the claims then lapse after
    their lease, and the original error is the one to show.
    """
    try:
        if heartbeat is not None:
            heartbeat.stop()
        if claimed:
            try:
                store.release_claims(owner)
            except MechoptError:
                if not quiet:
                    raise
    finally:
        try:
            if own_executor is not None:
                own_executor.close()
        finally:
            bar.close()
