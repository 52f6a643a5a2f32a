"""Refinement of the model's candidate by a constrained local search on the simulator itself (budgeted)."""

from __future__ import annotations

import time

import numpy as np

from mechopt.optimize.budget import BudgetExhausted, CountedProblem
from mechopt.optimize.sparse.local_search import local_slsqp
from mechopt.optimize.sparse.model_exploration import explore
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.optimize.sparse.stage import Stage
from mechopt.optimize.sparse.trust_region import trust_region_steps

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
    problem = CountedProblem(objective, space.box, budget, space.margins if space.problem.constraints else None)
    try:
        local_slsqp(problem, x0, fd_step=fd_step)
    except BudgetExhausted:
        pass
    finally:
        sampler.progress = progress
    x = np.asarray(problem.best_x if problem.best_x is not None else x0, dtype=float)
    simulated = float(sampler(x[None, :], desc="refinement")[0])
    return Stage(name="local refinement", plan=model_stage.plan, coverage=model_stage.coverage,
                 model=model_stage.model, line_designs=[], line_values=[], candidate=x,
                 predicted=float(model_stage.model.predict(x)[0]), simulated=simulated,
                 search_time_s=time.perf_counter() - t0, fit_time_s=0.0,
                 # Distinct new designs: the search may ask again for one simulated before it (its start).
                 n_samples=len(sampler.designs) - n_before)


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

    progress, sampler.progress = sampler.progress, False
    try:
        res = trust_region_steps(lambda Xc: model.model.predict(model.to_u(Xc)), simulate, space.feasible,
                                 space.box, X, f * f if square else f, budget, seed,
                                 space.margins if space.problem.constraints else None)
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
                       patience=space.dim + 1 if patience is None else patience)
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
