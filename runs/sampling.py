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
released (it was interrupted).  Claims are released when the call ends, however it ends.  That loop lives in
:mod:`~mechopt.runs.cooperative_evaluation`; this module prepares the request, evaluates one design in a worker
(:func:`evaluate_one`) and sums up the outcome.
"""

from __future__ import annotations

import functools
import json
import math
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from mechopt.errors import InfeasibleDesignError, InputError
from mechopt.runs.cooperative_evaluation import CooperativeEvaluation, is_final
from mechopt.runs.executors import SampleExecutor
from mechopt.runs.store import SampleRecord, SampleStore, as_design, design_key, utc_timestamp

if TYPE_CHECKING:  # runs/ needs only the problem's evaluate; the protocol lives above it, in optimize/
    from mechopt.optimize.problem import DesignProblem

__all__ = ["SamplingResult", "evaluate_one", "sample_designs"]

# Long enough for any useful message, short enough for a table cell or a log line.
_MAX_ERROR_CHARS = 500


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


@dataclass(frozen=True)
class _Request:
    """The designs of one call: validated, keyed and deduplicated, with the call's fingerprint and retry cut-off."""

    designs: list[tuple[float, ...]]
    keys: list[str]
    unique: dict[str, tuple[float, ...]]
    fingerprint: str
    redo_failed_before: str | None


def _request(designs: Iterable[Sequence[float]], problem: DesignProblem, fingerprint: str | None, retry_failed: bool,
             lease_s: float) -> _Request:
    """Check the arguments of :func:`sample_designs` and key its designs (InputError for an unusable one)."""
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
    return _Request(requested, keys, unique, fp, started_at if retry_failed else None)


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
    on_record: Callable[[SampleRecord], None] | None = None,
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
    on_record : callable, optional
        ``on_record(record)`` for each design this call settles (evaluated here or waited for), as it arrives;
        what it raises ends the call, with claims released and every result so far stored.

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
    request = _request(designs, problem, fingerprint, retry_failed, lease_s)
    fp, redo = request.fingerprint, request.redo_failed_before
    found = {k: r for k, r in store.get_keys(request.unique, fp).items() if is_final(r, redo)}
    pending = {k: d for k, d in request.unique.items() if k not in found}  # neither stored nor given up
    work = CooperativeEvaluation(store, fp, found, pending, n_cached=len(found), redo_failed_before=redo,
                                 lease_s=lease_s, on_record=on_record)
    if pending:
        work.run(functools.partial(evaluate_one, problem, fp), executor, progress=progress, desc=desc)
    return _sampling_result(request, work, start)


def _sampling_result(request: _Request, work: CooperativeEvaluation, start: float) -> SamplingResult:
    """The result of a call that began at ``start`` (``time.perf_counter()``, s), once every design is settled."""
    statuses = [work.found[k].status for k in request.unique]
    return SamplingResult(
        records=[work.found[k] for k in request.keys],
        n_requested=len(request.designs),
        n_unique=len(request.unique),
        n_cached=work.n_cached,
        n_computed=work.counts["computed"],
        n_failed=statuses.count("failed"),
        n_infeasible=statuses.count("infeasible"),
        n_waited=work.counts["waited"],
        wall_time_s=time.perf_counter() - start,
        compute_time_s=work.compute_time_s,
        executor=work.description,
    )
