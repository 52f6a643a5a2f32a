"""The final polish of the global plan on declared constraints: the GP's posterior mean minimised by SLSQP with the
constraint margins, from the incumbent, inside the polish box.

Random candidates filtered by the constraints almost never land on an active constraint, where the optimum of a
constrained design problem usually lies; SLSQP on the (cheap) model walks onto it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.optimize import minimize

from mechopt.optimize.auto.design_grid import NEIGHBOUR_RADIUS, DesignGrid
from mechopt.optimize.auto.gp import GaussianProcess
from mechopt.optimize.auto.held_polish import polished_neighbours

__all__ = ["nearest_feasible", "polish_on_constraints"]


def polish_on_constraints(gp: GaussianProcess, centre: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                          margins: Callable[[np.ndarray], np.ndarray],
                          allowed: Callable[[np.ndarray], np.ndarray],
                          grid: DesignGrid | None = None) -> np.ndarray | None:
    """The model's constrained minimiser near ``centre`` (unit cube), or None when it is not a new allowed design.

    Parameters
    ----------
    gp : GaussianProcess
        Model of the standardised targets.
    centre : (d,) ndarray
        Start (the incumbent).
    lo, hi : (d,) ndarray
        Polish box.
    margins : callable
        ``margins(U) -> (m, c)`` constraint margins (>= 0 feasible) of designs in unit-cube coordinates.
    allowed : callable
        Designs that may be simulated (declared constraints, not simulated yet).
    grid : DesignGrid, optional
        With discrete variables: the relaxed minimiser's neighbouring allowed designs, each also with its
        continuous variables polished (:func:`~mechopt.optimize.auto.held_polish.polished_neighbours`), are ranked
        by the model's mean, and the best one that may be simulated is returned (rounding the minimiser alone
        would often leave the constraint it lies on).
    """
    res = minimize(lambda u: float(gp.predict(u[None, :])[0][0]), centre, method="SLSQP",
                   bounds=list(zip(lo, hi, strict=True)),
                   constraints=[{"type": "ineq", "fun": lambda u: margins(u[None, :])[0]}],
                   options={"maxiter": 100, "ftol": 1e-10})
    x = np.clip(res.x, lo, hi)
    if grid is not None:
        N = polished_neighbours(lambda U: -gp.predict(U)[0], grid, x, lo, hi, NEIGHBOUR_RADIUS, margins)
        N = N[allowed(N)]
        return N[int(np.argmin(gp.predict(N)[0]))] if N.shape[0] else None
    return x if allowed(x[None, :])[0] else None


def nearest_feasible(u: np.ndarray, keep: int, margins: Callable[[np.ndarray], np.ndarray],
                     active: np.ndarray | None = None, origin: np.ndarray | None = None) -> np.ndarray | None:
    """The design nearest ``u`` (unit cube) with variable ``keep`` held at ``u[keep]`` that satisfies the declared
    constraints, with the constraints ``active`` (indices) held at their margins at ``origin`` (the design ``u`` was
    moved from); None when SLSQP finds none.

    A probe moved off a bound at a vertex of the bound and an active constraint either leaves the feasible region
    or leaves the constraint; the constrained optimum moves off the bound along the constraint, so the probe slides
    the other variables to stay on it.
    """
    d = u.size
    bounds = [(u[j], u[j]) if j == keep else (0.0, 1.0) for j in range(d)]
    constraints = [{"type": "ineq", "fun": lambda v: margins(v[None, :])[0]}]
    if active is not None and active.size and origin is not None:
        held = margins(origin[None, :])[0][active]
        constraints.append({"type": "eq", "fun": lambda v: margins(v[None, :])[0][active] - held})
    res = minimize(lambda v: float(np.sum((v - u) ** 2)), u, jac=lambda v: 2.0 * (v - u), method="SLSQP",
                   bounds=bounds, constraints=constraints, options={"maxiter": 100, "ftol": 1e-12})
    v = np.clip(res.x, 0.0, 1.0)
    v[keep] = u[keep]
    return v if np.all(margins(v[None, :])[0] >= 0.0) else None
