"""Differential evolution (scipy.optimize.differential_evolution, Storn & Price 1997) stopped at the budget.

Constraint handling: rejection through scipy's feasibility rules (Lampinen 2002).  The cheap margins are passed as a
``NonlinearConstraint``; scipy only calls the objective for trial vectors that satisfy them and ranks infeasible
ones by their violation, so the simulator never sees an infeasible design.  The box is enforced by scipy.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import NonlinearConstraint, OptimizeResult, differential_evolution

from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["minimize_differential_evolution"]


def minimize_differential_evolution(
    problem: CountedProblem,
    seed: int,
    *,
    popsize: int = 10,
    strategy: str = "best1bin",
    mutation: float | tuple[float, float] = (0.5, 1.0),
    recombination: float = 0.7,
    tol: float = 0.0,
    init: str = "latinhypercube",
    polish: bool = False,
) -> OptimizeResult:
    """Differential evolution run until the budget (or scipy's own convergence test) stops it.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of scipy's generator.
    popsize : int, default 10
        Population size multiplier (scipy's meaning: ``popsize * d`` members).
    strategy, mutation, recombination, init : see scipy.optimize.differential_evolution
    tol : float, default 0
        Relative convergence tolerance; 0 keeps evolving until the budget is spent or the population collapses.
    polish : bool, default False
        Polish the result with scipy's local solver (uses budget).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nit`` (scipy's
        generations when it stopped by itself, else -1).
    """

    def energy(x: np.ndarray) -> float:
        f = problem.evaluate(x)
        # A failed simulation is the worst possible energy, never a NaN that would break the comparisons.
        return f if math.isfinite(f) else math.inf

    constraints = ()
    if problem.has_constraints:
        constraints = (NonlinearConstraint(problem.margins, 0.0, np.inf),)
    # Each generation spends at most popsize * d calls; the cap only matters when scipy stops itself.
    maxiter = max(1, problem.budget)
    try:
        res = differential_evolution(
            energy, problem.bounds, strategy=strategy, maxiter=maxiter, popsize=popsize, tol=tol,
            mutation=mutation, recombination=recombination, rng=np.random.default_rng(seed), polish=polish,
            init=init, constraints=constraints,
        )
        return problem.result(f"scipy stopped: {res.message}", nit=int(res.nit))
    except BudgetExhausted as exc:
        return problem.result(str(exc), nit=-1)
