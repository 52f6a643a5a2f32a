"""COBYQA (Ragonneau 2022, scipy >= 1.14): a derivative-free trust-region method on quadratic models, multistart.

Constraint handling: native.  COBYQA receives the margins as a nonlinear constraint (cheap, not counted) and the box as
bounds, which it never leaves.  It may step outside the feasible region of the margins; such a design is not
simulated (unless the problem allows ``simulate_infeasible``) but valued by :meth:`CountedProblem.extended` from the
last feasible iterate, as for SLSQP.  Each start runs in the unit cube of the box with an equal share of the budget.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import NonlinearConstraint, OptimizeResult, minimize

from mechopt.optimize.budget import CountedProblem, run_multistart

__all__ = ["minimize_cobyqa"]


def minimize_cobyqa(
    problem: CountedProblem,
    seed: int,
    *,
    n_starts: int = 3,
    initial_tr_radius: float = 0.25,
    final_tr_radius: float = 1e-6,
) -> OptimizeResult:
    """Multistart COBYQA from seeded feasible Latin-hypercube starts, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the starts.
    n_starts : int, default 3
        Planned starts, each with an equal share of what is left; extra random starts use any budget left.
    initial_tr_radius : float, default 0.25
        First trust-region radius, in unit-cube coordinates (fraction of the box width).
    final_tr_radius : float, default 1e-6
        Radius at which a start has converged, in unit-cube coordinates.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nstarts``.
    """
    rng = np.random.default_rng(seed)
    starts = problem.sample_feasible(n_starts, rng)
    if starts.shape[0] == 0:
        return problem.result("no feasible start found", nstarts=0)

    def local_run(x0: np.ndarray) -> OptimizeResult:
        anchor = [np.asarray(x0, dtype=float)]

        def fun(u: np.ndarray) -> float:
            x = problem.from_unit(np.clip(u, 0.0, 1.0))
            if problem.feasible(x):
                anchor[0] = x
            f = problem.extended(x, anchor[0])
            return f if math.isfinite(f) else problem.infeasible_value

        constraints = ()
        if problem.has_constraints:
            constraints = (NonlinearConstraint(lambda u: problem.margins(problem.from_unit(u)), 0.0, np.inf),)
        return minimize(fun, problem.to_unit(anchor[0]), method="COBYQA", bounds=[(0.0, 1.0)] * problem.dim,
                        constraints=constraints,
                        options={"maxfev": max(problem.available, problem.dim + 2),
                                 "initial_tr_radius": initial_tr_radius, "final_tr_radius": final_tr_radius})

    n, message = run_multistart(problem, starts, local_run, rng=rng, min_share=problem.dim + 2)
    return problem.result(message, nstarts=n)
