"""Local search on the simulator: SLSQP with counted forward differences, steps on the feasible side.

The sparse model finds the basin of the optimum; where it is off by more than the tolerance, its candidate is only a
good start.  The objective near it is smooth, the optimum typically sits on a constraint, and a gradient method with
counted forward differences reaches it in a few dozen simulations.  Used by the pipeline's refinement and by the
SLSQP baseline.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.optimize import OptimizeResult, minimize

from mechopt.optimize.budget import CountedProblem

__all__ = ["feasible_side_gradient", "gradient_designs", "local_slsqp"]


def gradient_designs(problem: CountedProblem, x: np.ndarray, step: float = 1e-5) -> tuple[list[np.ndarray], list[bool]]:
    """The d designs :func:`feasible_side_gradient` asks for at ``x`` (and whether each is the forward one): known
    before any simulation, so that they can be simulated together."""
    x = np.asarray(x, dtype=float)
    points, forward_side = [], []
    for i in range(x.size):
        h = step * problem.span[i]
        forward, backward = x.copy(), x.copy()
        forward[i] += h
        backward[i] -= h
        forward_side.append(bool(problem.feasible(forward)[0] or not problem.feasible(backward)[0]
                                 and forward[i] <= problem.upper[i]))
        points.append(forward if forward_side[-1] else backward)
    return points, forward_side


def feasible_side_gradient(
    problem: CountedProblem, fun: Callable[[np.ndarray], float], x: np.ndarray, step: float = 1e-5
) -> np.ndarray:
    """Forward-difference gradient whose steps go to the feasible side of ``x`` when one exists.

    Parameters
    ----------
    problem : CountedProblem
        Gives the box and the cheap feasibility test.
    fun : callable
        Function of a design, normally counted (``d + 1`` calls, ``fun(x)`` usually cached).
    x : ndarray, shape (d,)
    step : float, default 1e-5
        Step as a fraction of the box width of each variable.

    Returns
    -------
    ndarray, shape (d,)
        Gradient in design units; a coordinate whose both neighbours are infeasible uses the forward step.
    """
    x = np.asarray(x, dtype=float)
    points, forward_side = gradient_designs(problem, x, step)
    prefetch = getattr(problem, "prefetch", None)
    if prefetch is not None:
        # A problem that can simulate several designs at once gets the d + 1 designs of the gradient together, as
        # one round of the workers; the calls below then find them.
        prefetch(np.vstack([x, *points]))
    f0 = fun(x)
    g = np.zeros(x.size)
    for i in range(x.size):
        h = step * problem.span[i]
        g[i] = (fun(points[i]) - f0) / h if forward_side[i] else (f0 - fun(points[i])) / h
    return g


def local_slsqp(
    problem: CountedProblem,
    x0: np.ndarray,
    *,
    fd_step: float = 1e-5,
    ftol: float = 1e-10,
    maxiter: int = 200,
) -> OptimizeResult:
    """One SLSQP run in the unit cube of the box with counted forward-difference gradients.

    Parameters
    ----------
    problem : CountedProblem
    x0 : ndarray, shape (d,)
        Feasible start.
    fd_step : float, default 1e-5
        Finite-difference step in unit-cube coordinates; raise it for a noisy simulator.
    ftol : float, default 1e-10
        SLSQP's tolerance on the objective.
    maxiter : int, default 200
        SLSQP iteration cap; the budget is enforced by the problem (raises :class:`BudgetExhausted`).

    Returns
    -------
    scipy.optimize.OptimizeResult
        scipy's result in unit-cube coordinates (the problem keeps the best feasible design anyway).
    """
    d = problem.dim
    anchor = [problem.clip(np.asarray(x0, dtype=float))]

    def extended(x: np.ndarray) -> float:
        if problem.feasible(x)[0]:
            anchor[0] = x
        f = problem.extended(x, anchor[0])
        return f if math.isfinite(f) else problem.infeasible_value

    def fun(u: np.ndarray) -> float:
        return extended(problem.from_unit(u))

    def gradient(u: np.ndarray) -> np.ndarray:
        # Chain rule of x = lower + u * span.
        return feasible_side_gradient(problem, extended, problem.from_unit(u), fd_step) * problem.span

    constraints = []
    if problem.has_constraints:
        constraints.append({"type": "ineq", "fun": lambda u: problem.margins(problem.from_unit(u))})
    return minimize(
        fun,
        np.clip(problem.to_unit(anchor[0]), 0.0, 1.0),
        jac=gradient,
        method="SLSQP",
        bounds=[(0.0, 1.0)] * d,
        constraints=constraints,
        options={"ftol": ftol, "maxiter": maxiter},
    )
