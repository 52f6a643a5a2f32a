"""Simulate many designs in parallel, resumably: stored results are reused, the rest computed and saved.

:func:`sample_designs` is the single entry point.  The simulator is any picklable top-level callable
``evaluate(design) -> dict`` with at least ``t_rms`` and ``t_max`` (N·m); it may raise
:class:`~sim.errors.InfeasibleDesignError` (recorded as ``infeasible``) or anything else (recorded as
``failed`` with a one-line message).  Neither stops the run.

Only the parent process writes to the store, one committed transaction per result, as results arrive.
Together with the executors' bounded submission this means a run killed at any time loses at most
``executor.max_in_flight`` computations and never computes a stored design again.
"""

from __future__ import annotations

import functools
import json
import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from mechopt.errors import InfeasibleDesignError
from tqdm.auto import tqdm

from .executors import SampleExecutor, make_executor
from .store import SampleRecord, SampleStore, as_design, design_key

__all__ = ["Evaluate", "SamplingResult", "evaluate_one", "sample_designs"]

#: The simulator: ``evaluate((oa, ab, bc)) -> {"t_rms": ..., "t_max": ..., ...}``.
Evaluate = Callable[[tuple[float, float, float]], dict[str, Any]]

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
        Number of distinct designs (by :func:`~studies.store.design_key`).
    n_cached : int
        Distinct designs found in the store, not simulated again.
    n_computed : int
        Distinct designs simulated by this call.
    n_failed, n_infeasible : int
        Distinct designs whose record (cached or new) is ``failed`` / ``infeasible``.
    wall_time_s : float
        Wall time of the whole call.
    compute_time_s : float
        Sum of the simulator wall times of the designs computed by this call (the serial cost; divided by
        ``wall_time_s`` it gives the achieved parallel speed-up).
    executor : str
        Description of the executor used (empty when nothing had to be computed).
    """

    records: list[SampleRecord]
    n_requested: int
    n_unique: int
    n_cached: int
    n_computed: int
    n_failed: int
    n_infeasible: int
    wall_time_s: float
    compute_time_s: float
    executor: str

    @property
    def n_ok(self) -> int:
        """Distinct designs simulated successfully (cached or new)."""
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


def _jsonable(value: Any) -> Any:
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON-serializable")


def evaluate_one(evaluate: Evaluate, settings_hash: str, design: tuple[float, float, float]) -> SampleRecord:
    """Run the simulator on one design and turn whatever happens into a record (runs in the worker).

    Parameters
    ----------
    evaluate : callable
        The simulator.
    settings_hash : str
        Settings hash to stamp on the record.
    design : tuple of 3 float
        ``(oa, ab, bc)`` in mm.

    Returns
    -------
    SampleRecord
        ``ok`` with ``t_rms``, ``t_max`` and the other returned keys in ``extra``; ``infeasible`` if the
        simulator raised :class:`~sim.errors.InfeasibleDesignError`; ``failed`` with the one-line
        ``"ExceptionType: message"`` of any other exception or of a malformed return value.  Never raises
        ``Exception``.
    """
    oa, ab, bc = design
    base = {"oa": oa, "ab": ab, "bc": bc, "settings_hash": settings_hash}
    start = time.perf_counter()
    try:
        out = evaluate(design)
    except InfeasibleDesignError as exc:
        return SampleRecord(
            **base,
            status="infeasible",
            error=_one_line(str(exc)) or "infeasible design",
            wall_time_s=time.perf_counter() - start,
        )
    except Exception as exc:
        message = _one_line(str(exc))
        return SampleRecord(
            **base,
            status="failed",
            error=_one_line(f"{type(exc).__name__}: {message}" if message else type(exc).__name__),
            wall_time_s=time.perf_counter() - start,
        )
    wall = time.perf_counter() - start
    try:
        if not isinstance(out, dict):
            raise TypeError(f"evaluate returned {type(out).__name__}, expected a dict with 't_rms' and 't_max'")
        values = {}
        for name in ("t_rms", "t_max"):
            if name not in out:
                raise ValueError(f"evaluate returned no {name!r}")
            values[name] = float(out[name])
            if not math.isfinite(values[name]):
                raise ValueError(f"evaluate returned a non-finite {name} = {values[name]!r}")
        extra_in = {k: v for k, v in out.items() if k not in values}
        # Round trip through JSON here, in the worker: what is stored is exactly what the caller gets back,
        # and a non-serializable value fails this design instead of the parent's write.
        extra = json.loads(json.dumps(extra_in, default=_jsonable))
    except Exception as exc:
        return SampleRecord(**base, status="failed", error=_one_line(f"{type(exc).__name__}: {exc}"), wall_time_s=wall)
    return SampleRecord(
        **base, status="ok", t_rms=values["t_rms"], t_max=values["t_max"], extra=extra, wall_time_s=wall
    )


def sample_designs(
    designs: Iterable[Sequence[float]],
    evaluate: Evaluate,
    store: SampleStore,
    settings_hash: str,
    executor: SampleExecutor | None = None,
    progress: bool = True,
    desc: str = "sampling",
) -> SamplingResult:
    """Simulate every design not yet in the store, save each result as it arrives, return all records.

    Parameters
    ----------
    designs : iterable of sequences of 3 float
        Designs ``(oa, ab, bc)`` in mm.  Duplicates (up to 1e-9 mm) are simulated once.
    evaluate : callable
        ``evaluate((oa, ab, bc)) -> dict`` with at least ``t_rms`` and ``t_max`` in N·m; further keys are kept
        in the record's ``extra`` and must be JSON-able.  Must be picklable (top-level function of an
        importable module, or a ``functools.partial`` of one) unless the executor is in-process.
    store : SampleStore
        Where results are looked up and written.
    settings_hash : str
        Hash of the settings ``evaluate`` embodies (:func:`~studies.store.settings_hash`); records of other
        settings are neither reused nor touched.
    executor : SampleExecutor, optional
        Where to run; default :func:`~studies.executors.make_executor` with every core, created only if there
        is something to compute, and closed at the end.  A given executor is left open.
    progress : bool, optional
        Show a tqdm bar with rate and ETA (default True; it stays silent anyway when stderr is not a
        terminal).
    desc : str, optional
        Label of the progress bar.

    Returns
    -------
    SamplingResult
        The records in the order of ``designs``, with counts and timings.

    Raises
    ------
    InputError
        If a design is not three finite numbers, or ``evaluate`` cannot be sent to the workers.
    StudyError
        If the executor itself failed (a worker process died); everything computed so far is saved.

    Notes
    -----
    Failed and infeasible designs are stored like the others and are not retried by later runs with the same
    settings hash.
    """
    start = time.perf_counter()
    requested = [as_design(d) for d in designs]
    keys = [design_key(d) for d in requested]
    unique: dict[str, tuple[float, float, float]] = {}
    for k, d in zip(keys, requested, strict=True):
        unique.setdefault(k, d)

    found = store.get_many(unique.values(), settings_hash)
    n_cached = len(found)
    todo = [d for k, d in unique.items() if k not in found]

    compute_time = 0.0
    description = ""
    if todo:
        own = executor is None
        ex = make_executor() if own else executor
        description = ex.description
        try:
            task = functools.partial(evaluate_one, evaluate, settings_hash)
            with tqdm(
                total=len(todo),
                desc=desc,
                unit="design",
                disable=None if progress else True,
                dynamic_ncols=True,
            ) as bar:
                bad = {"failed": 0, "infeasible": 0}
                bar.set_postfix(cached=n_cached, refresh=False)
                for record in ex.map_unordered(task, todo):
                    if not store.put(record):
                        # Another process stored this design meanwhile: its row is the reference.
                        record = store.get(record.design, settings_hash) or record
                    found[record.key] = record
                    compute_time += record.wall_time_s or 0.0
                    if not record.ok:
                        bad[record.status] += 1
                        bar.set_postfix(cached=n_cached, **bad, refresh=False)
                    bar.update(1)
        finally:
            if own:
                ex.close()

    by_status = [found[k].status for k in unique]
    return SamplingResult(
        records=[found[k] for k in keys],
        n_requested=len(requested),
        n_unique=len(unique),
        n_cached=n_cached,
        n_computed=len(todo),
        n_failed=by_status.count("failed"),
        n_infeasible=by_status.count("infeasible"),
        wall_time_s=time.perf_counter() - start,
        compute_time_s=compute_time,
        executor=description,
    )
