"""Multistart Nelder-Mead simplex search (scipy) from seeded feasible Latin-hypercube starts.

Constraint handling: rejection.  An infeasible vertex is never simulated; it gets
``infeasible_value + penalty * violation`` (:meth:`CountedProblem.penalised` with ``reject=True``), which the
simplex, comparing values only, treats as worse than any feasible design.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import OptimizeResult, minimize

from mechopt.optimize.budget import CountedProblem, run_multistart

__all__ = ["local_nelder_mead", "minimize_nelder_mead"]


def local_nelder_mead(
    problem: CountedProblem,
    x0: np.ndarray,
    *,
    step: float = 0.1,
    xatol: float = 1e-6,
    fatol: float = 1e-10,
    maxiter: int = 100_000,
) -> OptimizeResult:
    """One bounded Nelder-Mead run in the unit cube of the box, infeasible vertices rejected.

    Parameters
    ----------
    problem : CountedProblem
    x0 : ndarray, shape (d,)
        Feasible start.
    step : float, default 0.1
        Edge of the initial simplex as a fraction of the box width (pointed inwards at a face).
    xatol, fatol : float
        Convergence tolerances of scipy (``xatol`` in unit-cube coordinates).
    maxiter : int
        Iteration cap; the budget is enforced by the problem (raises :class:`BudgetExhausted`).

    Returns
    -------
    scipy.optimize.OptimizeResult
        scipy's result in unit-cube coordinates (the problem keeps the best feasible design anyway).
    """
    d = problem.dim
    u0 = np.clip(problem.to_unit(x0), 0.0, 1.0)
    simplex = np.repeat(u0[None, :], d + 1, axis=0)
    for i in range(d):
        # scipy's default simplex (5 % of each coordinate) depends on the origin of the units; use the box instead.
        simplex[i + 1, i] += step if u0[i] + step <= 1.0 else -step

    def fun(u: np.ndarray) -> float:
        return problem.penalised(problem.from_unit(u), reject=True)

    return minimize(
        fun,
        u0,
        method="Nelder-Mead",
        bounds=[(0.0, 1.0)] * d,
        options={"initial_simplex": simplex, "xatol": xatol, "fatol": fatol, "maxiter": maxiter,
                 "maxfev": problem.max_proposals},
    )


def minimize_nelder_mead(
    problem: CountedProblem,
    seed: int,
    *,
    n_starts: int = 5,
    step: float = 0.1,
    xatol: float = 1e-6,
    fatol: float = 1e-10,
) -> OptimizeResult:
    """Multistart Nelder-Mead with the budget split between seeded feasible Latin-hypercube starts.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the starts.
    n_starts : int, default 5
        Planned starts, each with an equal share of what is left; extra random starts use any budget left after a
        converged start.
    step, xatol, fatol : float
        See :func:`local_nelder_mead`.

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
        lambda x0: local_nelder_mead(problem, x0, step=step, xatol=xatol, fatol=fatol),
        rng=rng, min_share=problem.dim + 2,
    )
    return problem.result(message, nstarts=n)
