"""``mechopt.minimize``: one entry point for the sparse pipeline and every baseline, on any design problem."""

from __future__ import annotations

import contextlib
import os
import tempfile
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import BrokenSimulatorError, InfeasibleDesignError, InputError, MechoptError
from mechopt.optimize.arguments import (
    AUTO_METHOD,
    DEFAULT_METHOD,
    SPARSE_METHODS,
    check_budget,
    check_method,
    check_seed,
    check_workers,
    check_x0,
)
from mechopt.optimize.problem import DesignProblem
from mechopt.optimize.result import OptimizeResult
from mechopt.optimize.sparse.model_confidence import study_trust
from mechopt.optimize.sparse.options import SparseOptions
from mechopt.optimize.sparse.pipeline import run_pipeline
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.optimize.sparse.validate import validate
from mechopt.runs.early_stop import DEFAULT_STOP_AFTER_FAILURES, check_stop_after_failures
from mechopt.runs.executors import make_executor
from mechopt.runs.run_watch import watch_run
from mechopt.runs.store import SampleStore
from mechopt.runs.store_path import check_store_folder

__all__ = ["METHODS", "checked_options", "minimize", "parallel_accounting", "run_method"]

#: ``"sparse"``: the pipeline of paper 002 (global model, confirmation, local refinement) — for smooth landscapes;
#: ``"sparse-global"``: the same lines and blend made global on multimodal ones (basins of the blend and of its
#: leave-one-line-out uncertainty simulated, then steps on the blend corrected by every simulation;
#: :mod:`mechopt.optimize.sparse_global`).  Every
#: name of :data:`mechopt.optimize.baselines.BASELINES` is a method too.
METHODS = SPARSE_METHODS


def _baselines() -> dict[str, Callable[..., Any]]:
    from mechopt.optimize.baselines import BASELINES

    return BASELINES


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
    if isinstance(store, str | os.PathLike):
        check_store_folder(store, "store =")
    problem.check_region()


def minimize(problem: DesignProblem, budget: int = 600, method: str | Callable[..., Any] = DEFAULT_METHOD,
             seed: int = 0, workers: int | None = 1, store: str | Path | SampleStore | None = None,
             options: Mapping[str, Any] | SparseOptions | None = None, scheduler: Any = None,
             progress: bool = False, retry_failed: bool = False,
             log: Callable[[str], None] | None = None, x0: Any = None,
             stop_after_failures: int | None = DEFAULT_STOP_AFTER_FAILURES) -> OptimizeResult:
    """Minimise a design problem's objective within a budget of simulations.

    Parameters
    ----------
    problem : DesignProblem
        Variables, constraints, evaluator and objective.
    budget : int
        Most simulations the method may ask for (validation simulations of the sparse method come on top).
    method : str or callable
        ``"auto"`` (default: a plan chosen by dimension, budget and the problem's declaration, 2 to 12 variables,
        budgets from 2d + 2: Gaussian-process steps, in trust regions beyond 300 designs, or Gauss-Newton runs on the
        residuals of a least-squares problem; failed simulations learned and avoided; :mod:`mechopt.optimize.auto`),
        ``"sparse"`` (the line-sampled sparse model of paper 002, then a local search on the simulator; 2 to 4
        variables),
        ``"sparse-global"`` (for multimodal objectives: the lines' blend, its basins, then steps on the blend
        corrected by every simulation; :mod:`mechopt.optimize.sparse_global`), a
        baseline's name (``"slsqp"``, ``"differential_evolution"``...) or a callable
        ``f(counted_problem, seed) -> scipy OptimizeResult``.
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
        Options of the sparse method (``SparseOptions.help()``); defaults are scaled to the budget.
        ``validation_lines`` defaults to 0 here (no held-out lines).
    scheduler : str, optional
        A Dask scheduler address (or a client, or a ``LocalCluster``) to evaluate on instead of local processes;
        ``workers`` is then how many designs run at once there: ``workers=None`` for every worker thread of the
        cluster (the default 1 runs one at a time).
    progress : bool
        Progress bars with rate and ETA; when standard error is not a terminal (a log file, a pipe), one line at
        each tenth of the budget and at least every 30 s instead.
    retry_failed : bool
        Simulate again designs whose earlier simulation failed.
    log : callable, optional
        Where progress lines go (default: nowhere).
    x0 : (d,) or (m, d) array_like, optional
        Designs to simulate first, in the variables' units: the current design, earlier candidates.  They count in
        the budget, the result is never worse than the best of them, and ``"auto"`` fits its model to them in place
        of as many of its space-filling designs.  Inside the bounds and satisfying the declared constraints.
    stop_after_failures : int, optional
        Stop the run, with the first failure's reason, when its first this-many simulations all failed (default 5;
        with several workers the designs already running finish too); 0 or None never stops early.  Failures later
        in a run do not stop it: the methods learn where the simulator fails and avoid it.

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
        The first ``stop_after_failures`` simulations all failed.
    """
    _check_arguments(problem, budget, method, seed, workers, store)
    stop_after_failures = check_stop_after_failures(stop_after_failures)
    X0 = check_x0(problem, x0, int(budget))
    opts = checked_options(problem, method, options, int(budget), int(seed), X0)
    log = log or (lambda _line: None)
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        db = _open_store(store, stack)
        executor = stack.enter_context(make_executor(workers=workers, scheduler=scheduler))
        sampler = Sampler(problem, db, executor, progress, retry_failed)
        with watch_run(sampler, int(budget), progress=progress, stop_after_failures=stop_after_failures):
            result = run_method(problem, method, opts, sampler, log, x0=X0)
            if result.get("pipeline") is not None and opts.validation_lines > 0:  # not when handed to auto
                result["validation"] = validate(result.model, ModelSpace(problem), sampler, opts.validation_lines,
                                                opts.validation_points, opts.seed, f_min=result.fun)
                result["trust"] = study_trust(result.stages[0], result.pipeline.best, result.validation)
        _account(result, sampler)
    result["wall_time_s"] = time.perf_counter() - t0
    return result


def _account(result: OptimizeResult, sampler: Sampler) -> None:
    """What the run spent, reused and lost: counts, every failed design with its reason, the optimum's outputs.

    A run that found no design (every simulation failed, as when ``evaluate`` itself is wrong) says in its message
    why the first one failed: the count alone leaves the user to guess.
    """
    result["nnew"], result["nreused"] = sampler.n_computed, sampler.n_cached
    result["nfailed"] = len(sampler.failures)
    result["failures"] = [(np.array(d, dtype=float), error) for d, error in sampler.failures.values()]
    if result.success:
        record = sampler.records(np.asarray(result.x)[None, :], desc="optimum")[0]
        result["outputs"] = dict(record.outputs)
    elif result["failures"]:
        result["message"] = f"{result.message}; {result.nfailed} failed, the first with: {result.failures[0][1]}"
    result["sampling"] = sampler.summary()
    result.update(parallel_accounting(sampler))


def parallel_accounting(sampler: Sampler) -> dict[str, Any]:
    """``rounds``, ``batch_size``, ``idle_share``, ``waiting_s`` and ``method_s`` of a run so far (issue 28)."""
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
               log: Callable[[str], None], x0: np.ndarray | None = None) -> OptimizeResult:
    """Run one method on ``problem`` through ``sampler`` (its store and executor), within ``opts.budget``.

    The dispatch of :func:`minimize`, shared with ``mechopt study``; arguments are checked by the caller.

    Parameters
    ----------
    problem : DesignProblem
        The problem.
    method : str or callable
        A name of :func:`mechopt.optimize.arguments.available_methods` or ``f(counted_problem, seed)``.
    opts : SparseOptions
        The budget, the seed and the sparse method's settings.
    sampler : Sampler
        Where designs are simulated (and found again).
    log : callable
        Where progress lines go.
    x0 : (m, d) ndarray, optional
        Checked designs simulated first, on top of ``opts.budget`` (:func:`minimize` takes them out of its budget).

    Returns
    -------
    OptimizeResult
        Without ``validation`` (held-out lines are the caller's choice).
    """
    if x0 is None:
        return _run(problem, method, opts, sampler, log)
    if method == AUTO_METHOD:
        # Its model starts from them (they stand in for as many Sobol designs), which it simulates first: the best
        # of them is in its answer.
        return _auto(problem, int(opts.budget), int(opts.seed), sampler, initial=x0)
    values = sampler(x0, desc="x0")
    return _at_least_x0(_run(problem, method, opts, sampler, log), problem, x0, values)


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


def _run(problem: DesignProblem, method: str | Callable[..., Any], opts: SparseOptions, sampler: Sampler,
         log: Callable[[str], None]) -> OptimizeResult:
    if method == AUTO_METHOD:
        return _auto(problem, int(opts.budget), int(opts.seed), sampler)
    if method == "sparse":
        return _sparse(problem, opts, sampler, log)
    if method == "sparse-global":
        return _sparse_global(problem, int(opts.budget), int(opts.seed), sampler)
    fn = method if callable(method) else _baselines()[method]
    return _baseline(problem, fn, int(opts.budget), int(opts.seed), sampler,
                     method if isinstance(method, str) else getattr(fn, "__name__", "custom"))


def _sparse(problem: DesignProblem, opts: SparseOptions, sampler: Sampler, log: Callable[[str], None]):
    space = ModelSpace(problem)
    try:
        pipeline = run_pipeline(space, opts, sampler, log=log)
    except MechoptError as exc:
        if isinstance(exc, InputError | BrokenSimulatorError) or not sampler.failures:
            raise
        return _handed_to_auto(problem, opts, sampler, f"the line model could not be built ({exc})", log)
    success = bool(np.isfinite(pipeline.fun) and space.feasible(pipeline.x)[0])
    return OptimizeResult(x=pipeline.x, fun=pipeline.fun, nfev=len(sampler.designs), success=success,
                          message=pipeline.message, method="sparse", model=pipeline.stages[0].model,
                          stages=pipeline.stages, pipeline=pipeline, validation=None, options=opts,
                          trust=study_trust(pipeline.stages[0], pipeline.best, None))


def _sparse_global(problem: DesignProblem, budget: int, seed: int, sampler: Sampler) -> OptimizeResult:
    from mechopt.optimize.sparse_global import global_search

    def evaluate(X: np.ndarray) -> np.ndarray:
        return sampler(np.atleast_2d(X), desc="sparse-global")

    def margins(X: np.ndarray) -> np.ndarray:
        return problem.constraint_margins(np.atleast_2d(X))

    # A least-squares problem keeps a fifth of the budget for Gauss-Newton from the global phase's best design.
    local = max(5 * (problem.dim + 1), budget // 5) if problem.residuals and budget >= 60 else 0
    res = global_search(evaluate, problem.bounds, problem.feasible, problem.sampleable, budget=budget - local,
                        fit=problem.fit, seed=seed, margins=margins if problem.constraints else None,
                        batch=sampler.batch_size)
    x, fun = np.asarray(res.x, dtype=float), float(res.fun)
    trust = dict(res.trust)
    message = str(trust.get("verdict", ""))
    if local and np.all(np.isfinite(x)):
        from mechopt.optimize.least_squares import least_squares_polish

        x_ls, run = least_squares_polish(lambda X: sampler.residuals(X, desc="sparse-global: Gauss-Newton"),
                                         problem.bounds, x, budget - len(sampler.designs), problem.fd_step,
                                         batch=sampler.batch_size, feasible=problem.feasible,
                                         margins=margins if problem.constraints else None)
        if np.isfinite(run.value) and run.value < fun:
            x, fun = np.asarray(x_ls, dtype=float), float(run.value)
        message += f"; Gauss-Newton on the residuals from its best design: {fun:.6g} ({run.message})"
    success = bool(np.all(np.isfinite(x)) and problem.feasible(x)[0])
    return OptimizeResult(x=x, fun=fun, nfev=len(sampler.designs), success=success, message=message,
                          method="sparse-global", model=None, models=res.models, stages=[], validation=None,
                          trust=trust)


def _handed_to_auto(problem: DesignProblem, opts: SparseOptions, sampler: Sampler, why: str,
                    log: Callable[[str], None]) -> OptimizeResult:
    """The rest of the budget to the default method, which learns where the simulator fails, with every design the
    line model simulated as its start (failed simulations must not end a run: issue 22)."""
    left = int(opts.budget) - len(sampler.designs)
    log(f"  {why}: the remaining {left} simulations go to method 'auto'")
    initial = np.array([d for d, _ in sampler.history.values()]) if sampler.history else None
    result = _auto(problem, max(left, 0), int(opts.seed), sampler, initial=initial)
    result["message"] = f"{why}; {result.message}"
    result["method"] = "sparse"
    return result


def _auto(problem: DesignProblem, budget: int, seed: int, sampler: Sampler,
          initial: np.ndarray | None = None) -> OptimizeResult:
    from mechopt.optimize.auto import auto_search

    def evaluate(X: np.ndarray) -> np.ndarray:
        return sampler(np.atleast_2d(X), desc=AUTO_METHOD)

    def residuals(X: np.ndarray) -> tuple[np.ndarray, list]:
        return sampler.residuals(np.atleast_2d(X), desc=AUTO_METHOD)

    def margins(X: np.ndarray) -> np.ndarray:
        return problem.constraint_margins(np.atleast_2d(X))

    res = auto_search(evaluate, problem.bounds, budget, seed, feasible=problem.feasible,
                      batch=sampler.batch_size, margins=margins if problem.constraints else None,
                      residuals=residuals if problem.residuals else None, fd_step=problem.fd_step, initial=initial)
    success = bool(np.all(np.isfinite(res.x)) and problem.feasible(res.x)[0])
    return OptimizeResult(x=res.x, fun=res.fun, nfev=len(sampler.designs), success=success, message=res.message,
                          method=AUTO_METHOD, plan=res.plan.name, model=None, stages=[], validation=None)


def _baseline(problem: DesignProblem, fn: Callable[..., Any], budget: int, seed: int, sampler: Sampler,
              name: str) -> OptimizeResult:
    from mechopt.optimize.budget import CountedProblem

    def objective(x: np.ndarray) -> float:
        value = float(sampler(np.asarray(x, dtype=float)[None, :], desc=name)[0])
        if not np.isfinite(value):
            raise InfeasibleDesignError(f"the simulation of {problem.describe(x)} did not succeed")
        return value

    def margins(X: np.ndarray) -> np.ndarray:
        X = np.asarray(X, dtype=float)
        M = problem.constraint_margins(np.atleast_2d(X))
        return M[0] if X.ndim == 1 else M

    progress, sampler.progress = sampler.progress, False
    counted = CountedProblem(objective, problem.bounds, budget, margins if problem.constraints else None,
                             failure_errors=(InfeasibleDesignError,), vectorized_constraints=True)
    try:
        res = fn(counted, seed)
    finally:
        sampler.progress = progress
    x = counted.best_x
    success = x is not None
    return OptimizeResult(x=np.asarray(x if success else res.x, dtype=float), fun=float(counted.best_f) if success
                          else float("nan"), nfev=counted.nfev, success=success,
                          message=str(getattr(res, "message", "")) or ("done" if success else "no feasible design"),
                          method=name, model=None, stages=[], validation=None)
