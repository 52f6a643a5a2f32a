"""One Gauss-Newton run from a design, in the variables' units: the local phase of the line-model methods (and of
any caller with a residual evaluator) on a least-squares problem."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mechopt.optimize.least_squares.gauss_newton import LocalRun, gauss_newton
from mechopt.runs.sample_record import KEY_DECIMALS

__all__ = ["least_squares_polish"]

#: ``residuals(X) -> (values (n,), list of residual vectors or None)`` at designs X (n, d) in the variables' units.
XResiduals = Callable[[np.ndarray], tuple[np.ndarray, list]]


class _Counted:
    """The evaluator in unit-cube coordinates, each distinct design (to the store's resolution) counted once."""

    def __init__(self, residuals: XResiduals, bounds: np.ndarray, budget: int) -> None:
        self.residuals, self.budget = residuals, budget
        self.lo, self.width = bounds[:, 0], bounds[:, 1] - bounds[:, 0]
        self.seen: dict[tuple, tuple[float, np.ndarray | None]] = {}

    def key(self, u: np.ndarray) -> tuple:
        return tuple(np.round(self.lo + np.clip(u, 0.0, 1.0) * self.width, KEY_DECIMALS).tolist())

    def __call__(self, U: np.ndarray) -> tuple[np.ndarray, list]:
        U = np.atleast_2d(U)
        keys = [self.key(u) for u in U]
        # The designs themselves are simulated, not their rounded keys: a design on an active constraint rounded
        # to the store's resolution can fall outside it.
        first = {k: self.lo + np.clip(u, 0.0, 1.0) * self.width for k, u in zip(keys, U, strict=True)
                 if k not in self.seen}
        new = list(first)[: self.budget - len(self.seen)]
        if new:
            values, R = self.residuals(np.array([first[k] for k in new], dtype=float))
            for k, v, r in zip(new, values, R, strict=True):
                self.seen[k] = (float(v), None if r is None else np.asarray(r, dtype=float))
        n = next((i for i, k in enumerate(keys) if k not in self.seen), len(keys))
        return np.array([self.seen[k][0] for k in keys[:n]]), [self.seen[k][1] for k in keys[:n]]


def least_squares_polish(residuals: XResiduals, bounds: np.ndarray, x0: np.ndarray, budget: int, fd_step: float,
                         batch: int = 1, feasible: Callable[[np.ndarray], np.ndarray] | None = None,
                         margins: Callable[[np.ndarray], np.ndarray] | None = None) -> tuple[np.ndarray, LocalRun]:
    """Gauss-Newton from ``x0`` within ``budget`` distinct designs (``x0`` included).

    Parameters
    ----------
    residuals : callable
        ``residuals(X) -> (values, residual vectors or None)`` in the variables' units.
    bounds : (d, 2) ndarray
        Lower and upper bounds.
    x0 : (d,) ndarray
        Start, in the variables' units.
    budget : int
        Most distinct designs simulated (a design found in the sample store costs nothing, but is counted).
    fd_step : float
        Forward-difference step as a fraction of each variable's range.
    batch : int
        Designs simulated together.
    feasible : callable, optional
        ``feasible(X) -> bool (n,)``: the declared constraints.
    margins : callable, optional
        ``margins(X) -> (n, c)``: their margins (>= 0 feasible).

    Returns
    -------
    x : (d,) ndarray
        Best design reached, in the variables' units (``x0`` when it failed or the budget allowed nothing).
    run : LocalRun
        The run (unit-cube coordinates).
    """
    bounds = np.asarray(bounds, dtype=float)
    counted = _Counted(residuals, bounds, int(budget))
    lo, width = counted.lo, counted.width

    def to_x(U: np.ndarray) -> np.ndarray:
        return lo + np.clip(np.atleast_2d(U), 0.0, 1.0) * width

    u0 = (np.asarray(x0, dtype=float) - lo) / width
    values, R = counted(u0[None, :])
    if not len(R) or R[0] is None:
        return np.asarray(x0, dtype=float), LocalRun(u0, float("nan"), float("inf"), message="the start failed")
    run = gauss_newton(counted, u0, R[0], float(values[0]), budget=int(budget) - 1, step=fd_step, batch=batch,
                       allowed=None if feasible is None else (lambda U: feasible(to_x(U))),
                       margins=None if margins is None else (lambda U: margins(to_x(U))))
    return to_x(run.u)[0], run
