"""How :func:`mechopt.minimize` runs each kind of method on a problem through the sampler (its store and executor).

mechopt's own methods (``auto``, ``sparse``, ``sparse-global``) ask the sampler for batches of designs; a baseline
``f(counted_problem, seed, **options)`` asks for one design at a time through a
:class:`~mechopt.optimize.budget.CountedProblem`, which enforces its budget.  The table of methods
(:mod:`mechopt.optimize.methods`) names the runner of each.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mechopt.errors import BrokenSimulatorError, InfeasibleDesignError, InputError, MechoptError
from mechopt.optimize.problem import DesignProblem
from mechopt.optimize.result import OptimizeResult
from mechopt.optimize.sparse.model_confidence import study_trust
from mechopt.optimize.sparse.options import SparseOptions
from mechopt.optimize.sparse.pipeline import run_pipeline
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace

__all__ = ["MethodCall", "best_simulated", "run_auto", "run_baseline", "run_sparse", "run_sparse_global"]


@dataclass(frozen=True)
class MethodCall:
    """Everything one run of a method is given.

    Attributes
    ----------
    problem : DesignProblem
        The problem.
    opts : SparseOptions
        The budget (simulations) and the seed; the line model's settings for ``sparse``.
    sampler : Sampler
        Where designs are simulated (and found again in the store).
    log : callable
        Where progress lines go.
    name : str
        The method's name, for the progress and the result.
    options : mapping
        The method's own checked options (keyword arguments of a baseline).
    initial : (m, d) ndarray, optional
        Designs the method starts from (simulated first; only methods that take them).
    """

    problem: DesignProblem
    opts: SparseOptions
    sampler: Sampler
    log: Callable[[str], None]
    name: str
    options: Mapping[str, Any] = field(default_factory=dict)
    initial: np.ndarray | None = None

    @property
    def budget(self) -> int:
        """Most simulations the method may ask for."""
        return int(self.opts.budget)

    @property
    def seed(self) -> int:
        """Seed of every random choice."""
        return int(self.opts.seed)

    def margins(self) -> Callable[[np.ndarray], np.ndarray] | None:
        """The problem's constraint margins of a batch of designs, or None when it declares no constraint."""
        if not self.problem.constraints:
            return None
        return lambda X: self.problem.constraint_margins(np.atleast_2d(X))


def run_sparse(call: MethodCall) -> OptimizeResult:
    """Paper 002's line model, confirmation and refinement (:mod:`mechopt.optimize.sparse.pipeline`); when failed
    simulations leave too few lines to build it, the rest of the budget goes to ``auto``."""
    problem, opts, sampler = call.problem, call.opts, call.sampler
    space = ModelSpace(problem)
    try:
        pipeline = run_pipeline(space, opts, sampler, log=call.log)
    except MechoptError as exc:
        if isinstance(exc, InputError | BrokenSimulatorError) or not sampler.failures:
            raise
        return _handed_to_auto(call, f"the line model could not be built ({exc})")
    x, fun = best_simulated(problem, sampler, pipeline.x, pipeline.fun)
    success = bool(np.isfinite(fun) and space.feasible(x)[0])
    return OptimizeResult(x=x, fun=fun, nfev=len(sampler.designs), success=success,
                          message=pipeline.message, method=call.name, model=pipeline.stages[0].model,
                          stages=pipeline.stages, pipeline=pipeline, validation=None, options=opts,
                          trust=study_trust(pipeline.stages[0], pipeline.best, None))


def run_sparse_global(call: MethodCall) -> OptimizeResult:
    """The lines' blend made global (:mod:`mechopt.optimize.sparse_global`), then Gauss-Newton on the residuals of a
    least-squares problem."""
    from mechopt.optimize.sparse_global import global_search

    problem, sampler, budget = call.problem, call.sampler, call.budget

    def evaluate(X: np.ndarray) -> np.ndarray:
        return sampler(np.atleast_2d(X), desc=call.name)

    # A least-squares problem keeps a fifth of the budget for Gauss-Newton from the global phase's best design.
    local = max(5 * (problem.dim + 1), budget // 5) if problem.residuals and budget >= 60 else 0
    res = global_search(evaluate, problem.bounds, problem.feasible, problem.sampleable, budget=budget - local,
                        fit=problem.fit, seed=call.seed, margins=call.margins(), batch=sampler.batch_size)
    x, fun = np.asarray(res.x, dtype=float), float(res.fun)
    trust = dict(res.trust)
    message = str(trust.get("verdict", ""))
    if local and np.all(np.isfinite(x)):
        from mechopt.optimize.least_squares import least_squares_polish

        x_ls, run = least_squares_polish(lambda X: sampler.residuals(X, desc=f"{call.name}: Gauss-Newton"),
                                         problem.bounds, x, budget - len(sampler.designs), problem.fd_step,
                                         batch=sampler.batch_size, feasible=problem.feasible,
                                         margins=call.margins())
        if np.isfinite(run.value) and run.value < fun:
            x, fun = np.asarray(x_ls, dtype=float), float(run.value)
        message += f"; Gauss-Newton on the residuals from its best design: {fun:.6g} ({run.message})"
    x, fun = best_simulated(problem, sampler, x, fun)
    success = bool(np.all(np.isfinite(x)) and problem.feasible(x)[0])
    return OptimizeResult(x=x, fun=fun, nfev=len(sampler.designs), success=success, message=message,
                          method=call.name, model=None, models=res.models, stages=[], validation=None,
                          trust=trust)


def best_simulated(problem: DesignProblem, sampler: Sampler, x: np.ndarray, fun: float) -> tuple[np.ndarray, float]:
    """With discrete variables, the best feasible design the run simulated (every one is allowed: the sampler snaps
    them) and its value, instead of a method's own answer, which may be a proposal that was rounded; ``(x, fun)``
    unchanged when every variable is continuous."""
    if not sampler.discrete:
        return x, fun
    done = [(v, d) for d, v in sampler.history.values() if np.isfinite(v)]
    X = np.array([d for _, d in done]).reshape(-1, problem.dim)
    ok = problem.feasible(X) if X.shape[0] else np.zeros(0, dtype=bool)
    if not ok.any():
        return problem.snap(x) if np.all(np.isfinite(x)) else x, fun
    i = int(np.argmin(np.where(ok, [v for v, _ in done], np.inf)))
    return X[i].copy(), float(done[i][0])


def _handed_to_auto(call: MethodCall, why: str) -> OptimizeResult:
    """The rest of the budget to the default method, which learns where the simulator fails, with every design the
    line model simulated as its start (failed simulations must not end a run)."""
    from mechopt.optimize.methods import AUTO_METHOD

    sampler = call.sampler
    left = call.budget - len(sampler.designs)
    call.log(f"  {why}: the remaining {left} simulations go to method {AUTO_METHOD!r}")
    initial = np.array([d for d, _ in sampler.history.values()]) if sampler.history else None
    result = run_auto(MethodCall(call.problem, call.opts, sampler, call.log, AUTO_METHOD, initial=initial),
                      budget=max(left, 0))
    result["message"] = f"{why}; {result.message}"
    result["method"] = call.name
    return result


def run_auto(call: MethodCall, budget: int | None = None) -> OptimizeResult:
    """Gaussian-process steps on a plan chosen by dimension and budget (:mod:`mechopt.optimize.auto`), from
    ``call.initial`` when given; ``budget`` overrides the call's (what a handed-over run has left)."""
    from mechopt.optimize.auto import auto_search
    from mechopt.optimize.auto.design_grid import DesignGrid

    problem, sampler = call.problem, call.sampler

    def evaluate(X: np.ndarray) -> np.ndarray:
        return sampler(np.atleast_2d(X), desc=call.name)

    def residuals(X: np.ndarray) -> tuple[np.ndarray, list]:
        return sampler.residuals(np.atleast_2d(X), desc=call.name)

    res = auto_search(evaluate, problem.bounds, call.budget if budget is None else budget, call.seed,
                      feasible=problem.feasible, batch=sampler.batch_size, margins=call.margins(),
                      residuals=residuals if problem.residuals else None, fd_step=problem.fd_step,
                      initial=call.initial, grid=DesignGrid.of(problem))
    x = problem.snap(res.x) if np.all(np.isfinite(res.x)) else res.x  # exactly the allowed design simulated
    success = bool(np.all(np.isfinite(x)) and problem.feasible(x)[0])
    return OptimizeResult(x=x, fun=res.fun, nfev=len(sampler.designs), success=success, message=res.message,
                          method=call.name, plan=res.plan.name, model=None, stages=[], validation=None)


def run_baseline(call: MethodCall, fn: Callable[..., Any]) -> OptimizeResult:
    """A baseline ``fn(counted_problem, seed, **call.options)``, one design at a time through a
    :class:`~mechopt.optimize.budget.CountedProblem` that enforces the budget; the answer is the best feasible
    design it simulated."""
    from mechopt.optimize.budget import CountedProblem

    problem, sampler = call.problem, call.sampler

    def objective(x: np.ndarray) -> float:
        value = float(sampler(np.asarray(x, dtype=float)[None, :], desc=call.name)[0])
        if not np.isfinite(value):
            raise InfeasibleDesignError(f"the simulation of {problem.describe(x)} did not succeed")
        return value

    def margins(X: np.ndarray) -> np.ndarray:
        X = np.asarray(X, dtype=float)
        # The margins of the design that would be simulated: a method's feasibility test agrees with the door.
        M = problem.constraint_margins(problem.snap(np.atleast_2d(X)) if sampler.discrete else np.atleast_2d(X))
        return M[0] if X.ndim == 1 else M

    progress, sampler.progress = sampler.progress, False
    counted = CountedProblem(objective, problem.bounds, call.budget, margins if problem.constraints else None,
                             failure_errors=(InfeasibleDesignError,), vectorized_constraints=True,
                             snap=problem.snap if sampler.discrete else None)
    counted.variables = problem.variables  # the peers declare discrete variables in their libraries' own terms
    try:
        res = fn(counted, call.seed, **call.options)
    finally:
        sampler.progress = progress
    x = counted.best_x
    success = x is not None
    return OptimizeResult(x=np.asarray(x if success else res.x, dtype=float), fun=float(counted.best_f) if success
                          else float("nan"), nfev=counted.nfev, success=success,
                          message=str(getattr(res, "message", "")) or ("done" if success else "no feasible design"),
                          method=call.name, model=None, stages=[], validation=None)
