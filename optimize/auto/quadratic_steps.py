"""Trust-region steps of a full quadratic model (:mod:`~mechopt.optimize.auto.quadratic_model`) among the global
plan's expected-improvement steps, taken where a quadratic describes the designs and as long as they pay.

The step is the model's minimiser in a box of half-edge ``radius`` around the incumbent, the model fitted by least
squares to the 2p designs nearest it (p = (d + 1)(d + 2)/2 coefficients).  The radius follows Powell's ratio test:
the reduction achieved over the reduction the model predicted; above 3/4 with the step at the box's edge the box
doubles, below 1/4 it halves.

Whether the landscape near the incumbent is a valley the quadratic describes is learned, not assumed, in two ways:

* the model is used only where it predicts the designs it is fitted to, each left out in turn, with R² >= 0.9.
  Early in a run, or on a landscape of many wells, the nearest designs span several basins and no quadratic
  predicts them: the GP's expected improvement keeps exploring (a step whenever the last one paid, without this
  test, settled Styblinski-Tang and the cosine bowl into the basin of their first incumbent);
* a step that improves the incumbent is followed by another after the next expected-improvement step; after the
  j-th consecutive step that did not, the next waits 2^j expected-improvement steps, so that steps that do not pay
  cost about log2 of the budget.

On a valley the steps then take every other design, and the expected-improvement steps between them keep the search
global and the fitted designs spread.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mechopt.optimize.auto.quadratic_model import fit_quadratic, leave_one_out_r2, n_coefficients

__all__ = ["QuadraticSteps"]

#: Half-edge of the first box (unit cube): a tenth of the range each side, BOBYQA's usual ρ_beg.
START_RADIUS = 0.1
#: Smallest and largest half-edge (unit cube).
MIN_RADIUS, MAX_RADIUS = 1e-6, 0.5
#: Expected-improvement steps between two quadratic steps while they improve.
SUCCESS_WAIT = 1
#: Least leave-one-out R² of the quadratic on the designs nearest the incumbent for a step to be taken.
ADEQUATE_R2 = 0.9
#: Designs the model is fitted to, per coefficient (at most; at least d + 1 more than the coefficients, so that
#: the leave-one-out test has designs to spare).
DESIGNS_PER_COEFFICIENT = 2


class QuadraticSteps:
    """The state of the quadratic trust-region steps of one run.

    Parameters
    ----------
    dim : int
        Number of variables.
    """

    def __init__(self, dim: int) -> None:
        self.dim = dim
        self.radius = START_RADIUS
        #: Expected-improvement steps still to take before the next quadratic step, and consecutive failed steps.
        self.wait, self.misses = 0, 0
        self._pending: tuple[np.ndarray, float, float, float] | None = None

    def propose(self, U: np.ndarray, values: np.ndarray,
                allowed: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """The next quadratic step (1, d), or none (0, d) when it is not its turn or the model proposes no new
        allowed design.

        Parameters
        ----------
        U : (n, d) ndarray
            Designs simulated so far (unit cube).
        values : (n,) ndarray
            Their values (NaN: failed).
        allowed : callable
            ``allowed(U) -> bool (m,)``: designs that may be simulated.
        """
        none = np.zeros((0, self.dim))
        if self.wait > 0:
            self.wait -= 1
            return none
        ok = np.flatnonzero(np.isfinite(values))
        if not ok.size:
            return none
        best = ok[int(np.argmin(values[ok]))]
        centre = U[best]
        near = ok[np.argsort(np.max(np.abs(U[ok] - centre), axis=1))[: DESIGNS_PER_COEFFICIENT
                                                                      * n_coefficients(self.dim)]]
        if near.size <= n_coefficients(self.dim) + self.dim or not leave_one_out_r2(
                U[near], values[near], centre) >= ADEQUATE_R2:
            # No quadratic describes the designs near the incumbent (yet): the GP's steps explore.
            return none
        model = fit_quadratic(U[near], values[near], centre)
        if model is None:
            return none
        lo, hi = np.clip(centre - self.radius, 0.0, 1.0), np.clip(centre + self.radius, 0.0, 1.0)
        x = model.minimiser(lo, hi)
        predicted = model.value - float(model(x[None, :])[0])
        if predicted <= 0.0 or not allowed(x[None, :])[0]:
            # No descent the model believes in, or onto a design taken: a smaller box next time.
            self._missed()
            return none
        self._pending = (x, float(values[best]), predicted, float(np.max(np.abs(x - centre))))
        return x[None, :]

    def learn(self, U: np.ndarray, values: np.ndarray) -> None:
        """Take in the designs just simulated (U (m, d), values (m,)): the outcome of a pending step, if any."""
        if self._pending is None:
            return
        x, before, predicted, step = self._pending
        self._pending = None
        hit = np.flatnonzero(np.max(np.abs(U - x), axis=1) <= 1e-12)
        if not hit.size:
            return
        value = values[hit[0]]
        if np.isfinite(value) and value < before:
            ratio = (before - value) / predicted
            self.misses, self.wait = 0, SUCCESS_WAIT
            if ratio >= 0.75 and step >= 0.99 * self.radius:
                self.radius = min(2.0 * self.radius, MAX_RADIUS)
            elif ratio < 0.25:
                self.radius = max(0.5 * self.radius, MIN_RADIUS)
        else:
            self._missed()

    def _missed(self) -> None:
        """A step that did not improve: a smaller box, and a longer wait before the next."""
        self.radius = max(0.5 * self.radius, MIN_RADIUS)
        self.misses += 1
        self.wait = 2**self.misses
