"""Refinement of the model's candidate by a constrained local search on the simulator itself (budgeted)."""

from __future__ import annotations

import time

import numpy as np

from mechopt.optimize.budget import BudgetExhausted, CountedProblem
from mechopt.optimize.sparse.local_search import gradient_designs, local_slsqp
from mechopt.optimize.sparse.model_exploration import explore
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.optimize.sparse.stage import Stage
from mechopt.optimize.sparse.trust_region import trust_region_steps
from mechopt.runs.store import design_key

__all__ = ["corrected_steps", "model_steps", "refine_locally"]


def refine_locally(space: ModelSpace, sampler: Sampler, x0: np.ndarray, budget: int, model_stage: Stage,
                   fd_step: float = 1e-3) -> Stage:
    """SLSQP on the simulator from ``x0`` with the constraint margins as constraints, within ``budget`` calls.

    Where the global model is off by more than the tolerance, its candidate is only a good start: the objective
    near it is smooth, the optimum typically sits on a constraint, and a gradient method with counted forward
    differences reaches it in a few dozen simulations.

    Parameters
    ----------
    space : ModelSpace
        The problem's box and constraints.
    sampler : Sampler
        The simulator through the store (every call counted against ``budget``).
    x0 : (d,) ndarray
        Feasible start (the model's candidate).
    budget : int
        Most simulations.
    model_stage : Stage
        The model whose candidate is refined (its plan and model are kept for the report).
    fd_step : float
        Finite-difference step as a fraction of the box width: above the simulator's noise, below the curvature.

    Returns
    -------
    Stage
        ``candidate`` the best feasible design simulated, ``n_samples`` the simulations it took.
    """

    square = model_stage.model.fit == "square"

    def objective(x: np.ndarray) -> float:
        # The square of a non-negative objective has the same minimiser and no kink at a zero (a synthesis that can
        # reach its target exactly); it is what the model was fitted to.
        value = float(sampler(np.asarray(x, dtype=float)[None, :], desc="refinement")[0])
        return value * value if square else value

    progress, sampler.progress = sampler.progress, False
    t0 = time.perf_counter()
    n_before = len(sampler.designs)
    try:
        x = (_gauss_newton(space, sampler, x0, budget, fd_step) if space.problem.residuals
             else _slsqp(space, sampler, objective, x0, budget, fd_step))
    finally:
        sampler.progress = progress
    simulated = float(sampler(x[None, :], desc="refinement")[0])
    return Stage(name="local refinement", plan=model_stage.plan, coverage=model_stage.coverage,
                 model=model_stage.model, line_designs=[], line_values=[], candidate=x,
                 predicted=float(model_stage.model.predict(x)[0]), simulated=simulated,
                 search_time_s=time.perf_counter() - t0, fit_time_s=0.0,
                 # Distinct new designs: the search may ask again for one simulated before it (its start).
                 n_samples=len(sampler.designs) - n_before)


def _slsqp(space: ModelSpace, sampler: Sampler, objective, x0: np.ndarray, budget: int, fd_step: float
           ) -> np.ndarray:
    n_before = len(sampler.designs)

    def speculating(x: np.ndarray) -> float:
        _speculate(sampler, problem, x, fd_step, budget - (len(sampler.designs) - n_before))
        return objective(x)

    problem = _BatchedProblem(speculating if sampler.batch_size > 1 else objective, space.box, budget,
                              space.margins if space.problem.constraints else None)
    if sampler.batch_size > 1:
        problem.batch = lambda X: sampler(X, desc="refinement: gradient")
        problem.left = lambda: budget - (len(sampler.designs) - n_before)
    try:
        local_slsqp(problem, x0, fd_step=fd_step)
    except BudgetExhausted:
        pass
    return np.asarray(problem.best_x if problem.best_x is not None else x0, dtype=float)


def _gauss_newton(space: ModelSpace, sampler: Sampler, x0: np.ndarray, budget: int, fd_step: float) -> np.ndarray:
    """A least-squares problem: Gauss-Newton on its residuals (:mod:`mechopt.optimize.least_squares`), the
    Jacobian's differences simulated together."""
    from mechopt.optimize.least_squares import least_squares_polish

    problem = space.problem
    x, _ = least_squares_polish(lambda X: sampler.residuals(X, desc="refinement"), space.box, x0, budget, fd_step,
                                batch=sampler.batch_size, feasible=problem.feasible,
                                margins=problem.constraint_margins if problem.constraints else None)
    return np.asarray(x, dtype=float)


def _speculate(sampler: Sampler, problem: CountedProblem, x: np.ndarray, fd_step: float, left: int) -> None:
    """A new design of the search goes out with the d designs of its gradient, in one round.

    SLSQP asks for the gradient at nearly every design it simulates (the full step is accepted); the d + 1 designs
    then cost one round instead of two.  A design its line search rejects wastes its d gradient designs: the
    search then has fewer simulations left, never more than ``left`` in all.
    """
    x = np.asarray(x, dtype=float)
    if design_key(tuple(map(float, x))) in sampler.history:
        return
    if left <= 0:
        raise BudgetExhausted("the refinement's budget is spent")
    points = [p for p in gradient_designs(problem, x, fd_step)[0] if problem.feasible(p)[0]]
    sampler(np.vstack([x, *points])[:left], desc="refinement")


class _BatchedProblem(CountedProblem):
    """A counted problem whose finite-difference gradients simulate their d points as one batch.

    :func:`~mechopt.optimize.sparse.local_search.feasible_side_gradient` announces the designs it is about to ask
    for through :meth:`prefetch`; they are simulated together (at most what the budget still allows, in the order
    they will be asked for), and its calls then find them in the store.  The same designs as one at a time, so the
    same search: only the rounds differ.  Without ``batch`` (one worker) nothing is prefetched.
    """

    batch = None
    #: Simulations the refinement has left (speculated designs included), when it speculates.
    left = None

    def prefetch(self, X: np.ndarray) -> None:
        """Simulate together the feasible designs of X (k, d) not yet counted, within what the budget allows."""
        if self.batch is None:
            return
        todo, keys = [], set()
        left = self.available if self.left is None else min(self.available, self.left())
        for x in np.atleast_2d(np.asarray(X, dtype=float)):
            key = x.tobytes()
            if key in self._memo or key in keys:
                continue
            if left <= 0:
                break
            left -= 1  # an infeasible design costs one simulation too (its boundary point): counted, not fetched
            if self.feasible(x)[0]:
                keys.add(key)
                todo.append(x)
        if len(todo) > 1:
            self.batch(np.array(todo))


def model_steps(space: ModelSpace, sampler: Sampler, model_stage: Stage, budget: int, seed: int = 0) -> Stage:
    """Trust-region steps on the global model corrected by every simulation so far (:mod:`.trust_region`).

    Parameters
    ----------
    space : ModelSpace
        The problem's box and constraints.
    sampler : Sampler
        The simulator through the store (every step is one simulation, counted against ``budget``).
    model_stage : Stage
        The global model, its line samples and its simulated candidate.
    budget : int
        Most simulations.
    seed : int
        Seed of the points each step's search starts from.

    Returns
    -------
    Stage
        ``candidate`` the best design simulated by the steps or before them, ``n_samples`` the steps taken.
    """
    t0 = time.perf_counter()
    model = model_stage.model
    square = model.fit == "square"
    X = np.vstack([*model_stage.line_designs, model_stage.candidate[None, :]])
    f = np.concatenate([*model_stage.line_values, [model_stage.simulated]])

    def simulate(x: np.ndarray) -> float:
        value = float(sampler(np.asarray(x, dtype=float)[None, :], desc="model steps")[0])
        return value * value if square else value

    def simulate_batch(Xb: np.ndarray) -> np.ndarray:
        values = sampler(np.atleast_2d(Xb), desc="model steps")
        return values * values if square else values

    progress, sampler.progress = sampler.progress, False
    try:
        res = trust_region_steps(lambda Xc: model.model.predict(model.to_u(Xc)), simulate, space.feasible,
                                 space.box, X, f * f if square else f, budget, seed,
                                 space.margins if space.problem.constraints else None,
                                 batch=sampler.batch_size, simulate_batch=simulate_batch)
    finally:
        sampler.progress = progress
    x = np.asarray(res.x, dtype=float)
    simulated = float(np.sqrt(max(res.value, 0.0)) if square else res.value)
    return Stage(name="model steps", plan=model_stage.plan, coverage=model_stage.coverage, model=model,
                 line_designs=[], line_values=[], candidate=x, predicted=float(model.predict(x)[0]),
                 simulated=simulated, search_time_s=time.perf_counter() - t0, fit_time_s=0.0, n_samples=res.n_steps)


def corrected_steps(space: ModelSpace, sampler: Sampler, model_stage: Stage, budget: int, seed: int = 0,
                    patience: int | None = None) -> Stage:
    """Steps at the minimum of the global model corrected by every simulation of this run, after the local search.

    A finite-difference search stops where the simulator's noise hides the gradient; the corrected model
    (:func:`.model_exploration.corrected_model`: the blend plus a cubic radial-basis interpolant of its residuals at
    every design simulated so far) still sees the bottom of the basin from all those designs at once.  Each step
    simulates its minimum (distance 0 from the simulated designs, polished on the model under the margins).

    Parameters
    ----------
    space : ModelSpace
        The problem's box and constraints.
    sampler : Sampler
        The simulator through the store; its ``history`` is what the correction interpolates.
    model_stage : Stage
        The global model.
    budget : int
        Most simulations.
    seed : int
        Seed of the candidate clouds.
    patience : int, optional
        Stop after this many steps in a row without a better design (default d + 1, one gradient's worth).

    Returns
    -------
    Stage
        ``candidate`` the best design the run has simulated, ``n_samples`` the steps taken.
    """
    t0 = time.perf_counter()
    model = model_stage.model
    square = model.fit == "square"
    lower, span = space.box[:, 0], space.box[:, 1] - space.box[:, 0]
    X = np.array([d for d, _ in sampler.history.values()], dtype=float).reshape(-1, space.dim)
    values = np.array([v for _, v in sampler.history.values()], dtype=float)
    n_before = len(sampler.history)

    def simulate(z: np.ndarray) -> float:
        value = float(sampler((lower + z * span)[None, :], desc="corrected steps")[0])
        return value * value if square else value

    def simulate_batch(Zb: np.ndarray) -> np.ndarray:
        values = sampler(lower + np.atleast_2d(Zb) * span, desc="corrected steps")
        return values * values if square else values

    def trend(U: np.ndarray) -> np.ndarray:
        return model.model.predict(model.to_u(lower + np.atleast_2d(U) * span))

    def feasible(U: np.ndarray) -> np.ndarray:
        return np.asarray(space.feasible(lower + np.atleast_2d(U) * span), dtype=bool)

    def margins(U: np.ndarray) -> np.ndarray:
        return np.atleast_2d([space.margins(lower + u * span) for u in np.atleast_2d(U)])

    progress, sampler.progress = sampler.progress, False
    try:
        Z, q = explore(simulate, (X - lower) / span, values * values if square else values, trend, feasible,
                       budget, seed, (0.0,),
                       margins if space.problem.constraints else None,
                       patience=space.dim + 1 if patience is None else patience, batch=sampler.batch_size,
                       simulate_batch=simulate_batch)
    finally:
        sampler.progress = progress
    # The designs as simulated (the earlier ones exactly, not their round trip through the unit cube).
    X = np.vstack([X, lower + Z[n_before:] * span])
    ok = np.isfinite(q) & space.feasible(X)
    j = int(np.flatnonzero(ok)[np.argmin(q[ok])])
    x = X[j]
    simulated = float(np.sqrt(max(q[j], 0.0)) if square else q[j])
    return Stage(name="corrected steps", plan=model_stage.plan, coverage=model_stage.coverage, model=model,
                 line_designs=[], line_values=[], candidate=x, predicted=float(model.predict(x)[0]),
                 simulated=simulated, search_time_s=time.perf_counter() - t0, fit_time_s=0.0,
                 n_samples=len(sampler.history) - n_before)
