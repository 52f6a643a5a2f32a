"""Generalised simulated annealing (scipy.optimize.dual_annealing, Xiang et al. 1997) stopped at the budget.

Constraint handling: rejection.  scipy only knows the box; an infeasible visit is not simulated and gets
``infeasible_value + penalty * violation`` (:meth:`CountedProblem.penalised`), which the Metropolis test rejects.
The local phase is SLSQP with the cheap constraints and a feasible-side forward-difference gradient (counted),
because scipy's default L-BFGS-B, seeing only the rejection cliff, stalls short of an optimum on a constraint;
``local_search="l-bfgs-b"`` restores scipy's default.  The run starts at a seeded feasible design.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import OptimizeResult, dual_annealing

from mechopt.errors import InputError
from mechopt.optimize.budget import BudgetExhausted, CountedProblem
from mechopt.optimize.sparse.local_search import feasible_side_gradient

__all__ = ["minimize_dual_annealing"]


def minimize_dual_annealing(
    problem: CountedProblem,
    seed: int,
    *,
    initial_temp: float = 5230.0,
    restart_temp_ratio: float = 2e-5,
    visit: float = 2.62,
    accept: float = -5.0,
    no_local_search: bool = False,
    local_search: str = "slsqp",
    fd_step: float = 1e-5,
) -> OptimizeResult:
    """Dual annealing run until the budget (or scipy's iteration cap) stops it.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of scipy's generator and of the feasible start.
    initial_temp, restart_temp_ratio, visit, accept, no_local_search : see scipy.optimize.dual_annealing
    local_search : {"slsqp", "l-bfgs-b"}
        Local minimiser; SLSQP receives the constraints (used only when the problem has some).
    fd_step : float, default 1e-5
        Forward-difference step of the SLSQP gradient, as a fraction of the box width.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``.
    """
    if local_search not in ("slsqp", "l-bfgs-b"):
        raise InputError(f"local_search must be 'slsqp' or 'l-bfgs-b', got {local_search!r}")
    rng = np.random.default_rng(seed)

    def energy(x: np.ndarray) -> float:
        return problem.penalised(x, reject=True)

    minimizer_kwargs = None  # scipy's default L-BFGS-B
    if local_search == "slsqp" and problem.has_constraints:
        minimizer_kwargs = {
            "method": "SLSQP",
            "jac": lambda x: feasible_side_gradient(problem, energy, x, fd_step),
            "bounds": problem.bounds,
            "constraints": [{"type": "ineq", "fun": problem.margins}],
        }
    start = problem.sample_feasible(1, rng)
    if start.shape[0] == 0:
        return problem.result("no feasible start found")
    try:
        res = dual_annealing(
            energy, problem.bounds, minimizer_kwargs=minimizer_kwargs,
            maxiter=max(1, problem.budget), initial_temp=initial_temp, restart_temp_ratio=restart_temp_ratio,
            visit=visit, accept=accept, maxfun=problem.max_proposals, rng=rng, no_local_search=no_local_search,
            x0=start[0],
        )
        return problem.result(f"scipy stopped: {res.message[0] if isinstance(res.message, list) else res.message}")
    except BudgetExhausted as exc:
        return problem.result(str(exc))
