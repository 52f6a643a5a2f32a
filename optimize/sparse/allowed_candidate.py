"""The line model's candidate among the allowed designs: with discrete variables, the model is searched over the
grid points around its continuous minimum instead of rounding that minimum (which may leave the feasible region or
miss a better neighbour)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mechopt.optimize.auto.design_grid import DesignGrid
from mechopt.optimize.problem import DesignProblem

__all__ = ["best_allowed_near"]

#: Allowed values on each side of the rounded minimum that are searched on each discrete variable.
SEARCH_RADIUS = 3


def best_allowed_near(problem: DesignProblem, predict: Callable[[np.ndarray], np.ndarray], x: np.ndarray,
                      radius: int = SEARCH_RADIUS) -> np.ndarray:
    """The feasible allowed design of lowest predicted value near ``x`` (``x`` itself when every variable is
    continuous).

    Parameters
    ----------
    problem : DesignProblem
        Its variables' allowed values and its constraints.
    predict : callable
        ``predict(X) -> (n,)``: the model at designs X (n, d), in the variables' units.
    x : (d,) ndarray
        The model's minimum over the continuous box.
    radius : int
        Allowed values searched on each side of ``x``'s rounded value, per discrete variable.

    Returns
    -------
    (d,) ndarray
        An allowed design; ``x`` rounded when none near it is feasible (the caller checks feasibility).
    """
    grid = DesignGrid.of(problem)
    x = np.asarray(x, dtype=float)
    if grid is None or not np.all(np.isfinite(x)):
        return x
    for r in (radius, 3 * radius):
        X = problem.snap(grid.lo + grid.neighbourhood((x - grid.lo) / grid.width, r) * grid.width)
        X = X[problem.feasible(X)]
        if X.shape[0]:
            return X[int(np.argmin(np.asarray(predict(X), dtype=float)))]
    return problem.snap(x)
