"""Multistart SLSQP (scipy) with the cheap constraints passed as inequality constraints.

Constraint handling: native.  SLSQP receives the margins as ``ineq`` constraints (their finite-difference Jacobian
is cheap and not counted) and the box as bounds.  The objective gradient is a forward difference whose ``d`` extra
simulations are counted; each step goes to the feasible side of the design when one exists, so a simulator that is
undefined outside the feasible region is never called there.  An infeasible iterate of the line search is, unless
the problem allows ``simulate_infeasible``, valued by :meth:`CountedProblem.extended` from the last feasible
iterate (secant continuation from the boundary, one simulation of a feasible design).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.optimize.budget import CountedProblem, run_multistart
from mechopt.optimize.sparse.local_search import local_slsqp

__all__ = ["minimize_slsqp"]


def minimize_slsqp(
    problem: CountedProblem,
    seed: int,
    *,
    n_starts: int = 5,
    fd_step: float = 1e-5,
    ftol: float = 1e-10,
    maxiter: int = 200,
) -> OptimizeResult:
    """Multistart SLSQP with the budget split between seeded feasible Latin-hypercube starts.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the starts.
    n_starts : int, default 5
        Planned starts, each with an equal share of what is left; extra random starts use any budget left.
    fd_step, ftol, maxiter
        See :func:`local_slsqp`.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nstarts``.
    """
    rng = np.random.default_rng(seed)
    starts = problem.sample_feasible(n_starts, rng)
    if starts.shape[0] == 0:
        return problem.result("no feasible start found", nstarts=0)
    n, message = run_multistart(
        problem, starts,
        lambda x0: local_slsqp(problem, x0, fd_step=fd_step, ftol=ftol, maxiter=maxiter),
        rng=rng, min_share=problem.dim + 2,
    )
    return problem.result(message, nstarts=n)
