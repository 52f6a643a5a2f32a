"""The final polish of the global plan on declared constraints: the GP's posterior mean minimised by SLSQP with the
constraint margins, from the incumbent, inside the polish box.

Random candidates filtered by the constraints almost never land on an active constraint, where the optimum of a
constrained design problem usually lies; SLSQP on the (cheap) model walks onto it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.optimize import minimize

from mechopt.optimize.auto.gp import GaussianProcess

__all__ = ["polish_on_constraints"]


def polish_on_constraints(gp: GaussianProcess, centre: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                          margins: Callable[[np.ndarray], np.ndarray],
                          allowed: Callable[[np.ndarray], np.ndarray]) -> np.ndarray | None:
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
    """
    res = minimize(lambda u: float(gp.predict(u[None, :])[0][0]), centre, method="SLSQP",
                   bounds=list(zip(lo, hi, strict=True)),
                   constraints=[{"type": "ineq", "fun": lambda u: margins(u[None, :])[0]}],
                   options={"maxiter": 100, "ftol": 1e-10})
    x = np.clip(res.x, lo, hi)
    return x if allowed(x[None, :])[0] else None
