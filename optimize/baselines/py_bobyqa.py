"""Py-BOBYQA (Cartis, Fiala, Marteau & Roberts 2019; Powell's BOBYQA, 2009): a derivative-free trust-region method
on quadratic models interpolating 2d + 1 points, bounds only, as a budget-limited baseline.

Configuration: ``pybobyqa.solve(f, x0, bounds=([0]*d, [1]*d), maxfun=remaining)`` in the unit cube of the box, with
the library's defaults (``npt = 2d + 1``, ``rhobeg`` = 0.1, ``rhoend`` = 1e-8) and its own restarts switched on
(``restarts.use_restarts``: when ρ reaches ρ_end the method restarts from its best point with a larger trust region,
the documented way of spending a budget on a problem it has solved locally).  x0 is a seeded feasible
Latin-hypercube design; should a run still end with simulations left, the next one starts from the best design,
or from a fresh seeded feasible design when a run simulated nothing new.

Constraint handling: Py-BOBYQA only takes bounds; the margins are handled as for COBYQA and SLSQP here: an infeasible
iterate is not simulated but valued by :meth:`CountedProblem.extended`, the secant continuation from the last
feasible iterate.  Needs the ``compare`` extra.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.optimize.baselines.library import require
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["minimize_py_bobyqa"]


def minimize_py_bobyqa(
    problem: CountedProblem, seed: int, *, rhobeg: float = 0.1, rhoend: float = 1e-8
) -> OptimizeResult:
    """Py-BOBYQA from a seeded feasible start, with its restarts, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the start.
    rhobeg : float, default 0.1
        First trust-region radius, in unit-cube coordinates (fraction of the box width; the library's default).
    rhoend : float, default 1e-8
        Radius at which a run has converged (before it restarts), in unit-cube coordinates.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nruns`` (solver
        calls: later ones start from the best design, or afresh).
    """
    pybobyqa = require("pybobyqa", "py_bobyqa")
    rng = np.random.default_rng(seed)
    starts = problem.sample_feasible(1, rng)
    if starts.shape[0] == 0:
        return problem.result("no feasible start found", nruns=0)
    anchor = [starts[0]]

    def fun(u: np.ndarray) -> float:
        x = problem.from_unit(np.clip(u, 0.0, 1.0))
        if problem.feasible(x)[0]:
            anchor[0] = x
        f = problem.extended(x, anchor[0])
        return f if math.isfinite(f) else problem.infeasible_value

    message, runs, x0 = "budget spent", 0, starts[0]
    lower, upper = np.zeros(problem.dim), np.ones(problem.dim)
    try:
        while problem.remaining > 0:
            runs += 1
            spent = problem.nfev
            with warnings.catch_warnings():
                # "maxfun <= npt" when the last simulations of the budget are fewer than the model's points.
                warnings.simplefilter("ignore", RuntimeWarning)
                pybobyqa.solve(fun, problem.to_unit(x0), bounds=(lower, upper), maxfun=problem.remaining,
                               rhobeg=rhobeg, rhoend=rhoend, do_logging=False,
                               user_params={"restarts.use_restarts": True})
            if problem.nfev > spent and problem.best_x is not None:
                x0 = problem.best_x
                continue
            # Every design of the run was already simulated (its restarts circle a solved minimum): a fresh start.
            fresh = problem.sample_feasible(1, rng)
            if fresh.shape[0] == 0:
                message = "no further feasible start"
                break
            x0 = fresh[0]
    except BudgetExhausted as exc:
        message = str(exc)
    return problem.result(message, nruns=runs)
