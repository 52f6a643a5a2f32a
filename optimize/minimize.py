"""``mechopt.minimize``: one entry point for the sparse pipeline and every baseline, on any design problem."""

from __future__ import annotations

import contextlib
import dataclasses
import os
import tempfile
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.analysis.robust_result import checked_robust, make_robust
from mechopt.optimize.analysis.scatter import Tolerances
from mechopt.optimize.arguments import check_budget, check_method, check_seed, check_workers, check_x0
from mechopt.optimize.method_runs import MethodCall
from mechopt.optimize.methods import AUTO_METHOD, DEFAULT_METHOD, check_options, get_method
from mechopt.optimize.problem import DesignProblem
from mechopt.optimize.result import OptimizeResult
from mechopt.optimize.sparse.model_confidence import study_trust
from mechopt.optimize.sparse.options import SparseOptions
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.optimize.sparse.validate import validate
from mechopt.optimize.trade_off import check_trade_off_method, run_trade_off
from mechopt.runs.early_stop import DEFAULT_STOP_AFTER_FAILURES, check_stop_after_failures
from mechopt.runs.executors import make_executor
from mechopt.runs.run_watch import watch_run
from mechopt.runs.store import SampleStore
from mechopt.runs.store_path import check_store_folder

__all__ = ["checked_options", "minimize", "parallel_accounting", "run_method"]


def _check_arguments(problem: Any, budget: Any, method: Any, seed: Any, workers: Any, store: Any) -> None:
    if not isinstance(problem, DesignProblem):
        raise InputError(f"problem must be a mechopt.DesignProblem, got {type(problem).__name__}")
    problem.check()
    check_budget(budget)
    check_method(method, problem.dim, problem.name)
    check_seed(seed)
    check_workers(workers)
    if store is not None and not isinstance(store, str | os.PathLike | SampleStore):
        raise InputError(f"store = {store!r}: expected the path of an SQLite file or a SampleStore")
    check_trade_off_method(problem, method)
    if isinstance(store, str | os.PathLike):
        check_store_folder(store, "store =")
    problem.check_region()


def minimize(problem: DesignProblem, budget: int = 600, method: str | Callable[..., Any] = DEFAULT_METHOD,
             seed: int = 0, workers: int | None = 1, store: str | Path | SampleStore | None = None,
             options: Mapping[str, Any] | SparseOptions | None = None, scheduler: Any = None,
             progress: bool = False, retry_failed: bool = False, tolerances: Any = None,
             log: Callable[[str], None] | None = None, x0: Any = None, max_violation: float = 0.01,
             stop_after_failures: int | None = DEFAULT_STOP_AFTER_FAILURES) -> OptimizeResult:
    """Minimise a design problem's objective within a budget of simulations.

    Parameters
    ----------
    problem : DesignProblem
        Variables, constraints, evaluator and objective.
    budget : int
        Most simulations the method may ask for (validation simulations of the sparse method come on top).
    method : str or callable
        A name of the table of methods (:mod:`mechopt.optimize.methods`; ``mechopt methods`` lists each with what
        it takes), ``"auto"`` by default, or a callable ``f(counted_problem, seed) -> scipy OptimizeResult``.
    seed : int
        Seed of every random choice.
    workers : int, optional
        Local processes evaluating designs; 1 (default) runs in this process.  None uses every core.  The mechopt
        methods (``"auto"``, ``"sparse"``, ``"sparse-global"``) propose as many designs at once as there are workers
        (Dask: the cluster's worker threads); with one worker they behave exactly as one at a time.
    store : path or SampleStore, optional
        SQLite sample store: designs found there (same problem fingerprint) are not simulated again, and every new
        one is committed as soon as it is known.  Default: a temporary store, discarded at the end.
    options : mapping or SparseOptions, optional
        The method's options (``mechopt methods NAME``); an unknown one is refused.  The sparse method's are scaled
        to the budget, and its ``validation_lines`` defaults to 0 here (no held-out lines).
    scheduler : str, optional
        A Dask scheduler address (or a client, or a ``LocalCluster``) to evaluate on instead of local processes;
        ``workers`` is then how many designs run at once there: ``workers=None`` for every worker thread of the
        cluster (the default 1 runs one at a time).
    progress : bool
        Progress bars; log lines (each tenth of the budget, at least every 30 s) when stderr is not a terminal.
    retry_failed : bool
        Simulate again designs whose earlier simulation failed.
    log : callable, optional
        Where progress lines go (default: nowhere).
    x0 : (d,) or (m, d) array_like, optional
        Designs to simulate first, in the variables' units: the current design, earlier candidates.  They count in
        the budget, the result is never worse than the best of them, and ``"auto"`` fits its model to them in place
        of as many of its space-filling designs.  Inside the bounds and satisfying the declared constraints.
    tolerances, max_violation : mapping or Tolerances, and float in (0, 0.5), optional
        ``x`` becomes the robust optimum under ± tolerances (``{"oa": 0.1}``): :mod:`mechopt.optimize.analysis.robust`.
    stop_after_failures : int, optional
        Stop when the first this-many simulations all failed (default 5; 0 or None: never); later failures do not.

    Returns
    -------
    OptimizeResult
        ``x``, ``fun``, ``outputs``, ``nfev``, ``success``, ``message``, ``nfailed`` and ``failures`` (each failed
        design, in the variables' units, with the reason), the accounting of the parallel run
        (``rounds``, ``batch_size``, ``idle_share``, ``waiting_s``, ``method_s``) and, for the sparse method,
        ``model``, ``stages`` and ``validation``.

    Raises
    ------
    InputError
        A bad argument, before any simulation.
    BrokenSimulatorError
        The first ``stop_after_failures`` simulations all failed (``mechopt.errors``).
    """
    X0, opts, own, tols = _checked(problem, budget, method, seed, workers, store, x0, options, tolerances,
                                   max_violation)
    t0, log = time.perf_counter(), log or (lambda _line: None)
    stop_after_failures = check_stop_after_failures(stop_after_failures)
    with contextlib.ExitStack() as stack:
        db = _open_store(store, stack)
        executor = stack.enter_context(make_executor(workers=workers, scheduler=scheduler))
        sampler = Sampler(problem, db, executor, progress, retry_failed)
        with watch_run(sampler, int(budget), progress=progress, stop_after_failures=stop_after_failures):
            result = _validated(run_method(problem, method, opts, sampler, log, x0=X0, options=own), problem, opts,
                                sampler)
        _account(result, sampler)
        make_robust(problem, result, sampler, tols, max_violation, log)
    result["wall_time_s"] = time.perf_counter() - t0
    return result


def _checked(problem: DesignProblem, budget: int, method: Any, seed: int, workers: Any, store: Any, x0: Any,
             options: Any, tolerances: Any,
             max_violation: Any) -> tuple[Any, SparseOptions, dict[str, Any], Tolerances | None]:
    """Every argument of :func:`minimize` checked before any simulation: x0, the options, the tolerances."""
    _check_arguments(problem, budget, method, seed, workers, store)
    X0 = check_x0(problem, x0, int(budget))
    opts, own = _split_options(problem, method, options, int(budget), int(seed), X0)
    return X0, opts, own, checked_robust(problem, tolerances, max_violation)


def _validated(result: OptimizeResult, problem: DesignProblem, opts: SparseOptions,
               sampler: Sampler) -> OptimizeResult:
    """``result`` with the held-out validation of its line model when asked for (not when handed to auto)."""
    if result.get("pipeline") is not None and opts.validation_lines > 0:
        result["validation"] = validate(result.model, ModelSpace(problem), sampler, opts.validation_lines,
                                        opts.validation_points, opts.seed, f_min=result.fun)
        result["trust"] = study_trust(result.stages[0], result.pipeline.best, result.validation)
    return result


def _split_options(problem: DesignProblem, method: str | Callable[..., Any],
                   options: Mapping[str, Any] | SparseOptions | None, budget: int, seed: int,
                   x0: np.ndarray | None) -> tuple[SparseOptions, dict[str, Any]]:
    """The run's SparseOptions (budget, seed, and the line model's settings) and the method's own checked options:
    a line model's options are its SparseOptions, any other method's are checked against its record."""
    whole = get_method(method).line_model or isinstance(options, SparseOptions)
    own = {} if whole else check_options(method, options)
    return checked_options(problem, method, options if whole else None, budget, seed, x0), own


def _account(result: OptimizeResult, sampler: Sampler) -> None:
    """What the run spent, reused and lost: counts, every failed design with its reason, the optimum's outputs.

    A run that found no design (every simulation failed, as when ``evaluate`` itself is wrong) says in its message
    why the first one failed: the count alone leaves the user to guess.
    """
    result["nnew"], result["nreused"] = sampler.n_computed, sampler.n_cached
    result["nfailed"] = len(sampler.failures)
    result["failures"] = [(np.array(d, dtype=float), error) for d, error in sampler.failures.values()]
    if result.success and np.ndim(result.x) == 1:
        record = sampler.records(np.asarray(result.x)[None, :], desc="optimum")[0]
        result["outputs"] = dict(record.outputs)
    elif result["failures"]:
        result["message"] = f"{result.message}; {result.nfailed} failed, the first with: {result.failures[0][1]}"
    result["sampling"] = sampler.summary()
    result.update(parallel_accounting(sampler))


def parallel_accounting(sampler: Sampler) -> dict[str, Any]:
    """``rounds``, ``batch_size``, ``idle_share``, ``waiting_s`` and ``method_s`` of a run so far."""
    timing = sampler.timing()
    return {"rounds": timing["rounds"], "batch_size": sampler.batch_size, "idle_share": timing["idle_share"],
            "waiting_s": timing["waiting_s"], "method_s": timing["method_s"]}


def _options(problem: DesignProblem, options: Mapping[str, Any] | SparseOptions | None, budget: int,
             seed: int) -> SparseOptions:
    """The sparse options of a call: given whole, or scaled to the budget (no held-out lines unless asked)."""
    if isinstance(options, SparseOptions):
        return options.replace(budget=budget, seed=seed)
    given = dict(options or {})
    given.setdefault("validation_lines", 0)
    return SparseOptions.for_budget(budget, problem.dim, seed, **given)


def checked_options(problem: DesignProblem, method: str | Callable[..., Any],
                    options: Mapping[str, Any] | SparseOptions | None, budget: int, seed: int,
                    x0: np.ndarray | None = None) -> SparseOptions:
    """The options of :func:`_options` for what ``x0`` leaves of the budget; a budget below the method's minimum is
    refused on them, since the sparse method's minimum depends on its lines, which the options may set (shared with
    ``mechopt study --x0``)."""
    m = 0 if x0 is None else x0.shape[0]
    opts = _options(problem, options, budget - m, seed)
    try:
        check_method(method, problem.dim, problem.name, opts.budget, n_lines=opts.n_lines)
    except InputError as exc:
        if not m:
            raise
        raise InputError(f"x0's {m} designs count in budget = {budget}, which leaves {budget - m} to the method: "
                         f"{exc}") from None
    return opts


def _open_store(store: str | Path | SampleStore | None, stack: contextlib.ExitStack) -> SampleStore:
    """The caller's store, a store at the caller's path, or a temporary one removed when ``stack`` closes."""
    if isinstance(store, SampleStore):
        return store
    if store is None:
        store = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="mechopt-"))) / "samples.sqlite"
    return stack.enter_context(SampleStore(store))


def run_method(problem: DesignProblem, method: str | Callable[..., Any], opts: SparseOptions, sampler: Sampler,
               log: Callable[[str], None], x0: np.ndarray | None = None,
               options: Mapping[str, Any] | None = None) -> OptimizeResult:
    """Run one method on ``problem`` through ``sampler`` (its store and executor), within ``opts.budget``.

    The dispatch of :func:`minimize` through the table of methods (:data:`mechopt.optimize.methods.METHODS`), shared
    with ``mechopt study``; arguments are checked by the caller.

    Parameters
    ----------
    problem : DesignProblem
        The problem.
    method : str or callable
        A name of :func:`mechopt.optimize.methods.available_methods` or ``f(counted_problem, seed, **options)``.
    opts : SparseOptions
        The budget, the seed and the sparse method's settings.
    sampler : Sampler
        Where designs are simulated (and found again).
    log : callable
        Where progress lines go.
    x0 : (m, d) ndarray, optional
        Checked designs simulated first, on top of ``opts.budget`` (:func:`minimize` takes them out of its budget).
    options : mapping, optional
        The method's own checked options (:func:`mechopt.optimize.methods.check_options`).

    Returns
    -------
    OptimizeResult
        Without ``validation`` (held-out lines are the caller's choice).
    """
    if method == AUTO_METHOD and problem.trade_off:
        # Several objectives or limits on simulated outputs: x0 counts in the budget, as for the other plans.
        return run_trade_off(problem, int(opts.budget) + (0 if x0 is None else len(x0)), int(opts.seed), sampler,
                             initial=x0, scalarise=dict(options or {}).get("front") == "parego")
    record = get_method(method)
    call = MethodCall(problem, opts, sampler, log, record.name, dict(options or {}))
    if x0 is None:
        return record.run(call)
    if record.starts_from_x0:
        # Its model starts from them (they stand in for as many space-filling designs), which it simulates first:
        # the best of them is in its answer.
        return record.run(dataclasses.replace(call, initial=x0))
    values = sampler(x0, desc="x0")
    return _at_least_x0(record.run(call), problem, x0, values)


def _at_least_x0(result: OptimizeResult, problem: DesignProblem, x0: np.ndarray,
                 values: np.ndarray) -> OptimizeResult:
    """``result``, or the best design of ``x0`` when the method found nothing better: the answer is never worse
    than the design the user started from."""
    if not np.isfinite(values).any():
        return result
    i = int(np.nanargmin(values))
    if result.success and np.isfinite(result.fun) and result.fun <= values[i]:
        return result
    result.update(x=np.array(x0[i], dtype=float), fun=float(values[i]), success=True,
                  message=f"{result.message}; a design of x0 stays the best ({problem.describe(x0[i])})")
    return result
