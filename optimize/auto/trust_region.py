"""A trust region in the unit cube that grows after successes and shrinks after failures (TuRBO: Eriksson et al.
2019), restarted elsewhere once it has shrunk below a minimum.

Beyond the global GP's size (:data:`~mechopt.optimize.auto.plan.GLOBAL_MAX_POINTS`) the search goes on locally: a
box around the incumbent, stretched along the variables the GP finds the objective slowly varying in, keeps the
model local (fitted to the designs nearest the centre) and the steps where it is accurate; a sharp minimum is
refined there better than by one stationary model of the whole box.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["TrustRegion"]


@dataclass
class TrustRegion:
    """State of one trust region.

    Parameters
    ----------
    dim : int
        Number of variables.
    batch : int
        Designs simulated per step (the failure tolerance is counted in steps).
    length : float
        Edge of the box (unit cube units, before stretching), 0.8 at start.
    floor : (d,) ndarray, optional
        Least half-edge on each variable (unit cube): one allowed value on a discrete variable, so that a box
        never shrinks to hold none but the centre's.
    """

    dim: int
    batch: int = 1
    length: float = 0.8
    length_min: float = 0.5**7
    length_max: float = 1.6
    successes: int = 0
    failures: int = 0
    success_tol: int = 3
    floor: np.ndarray | None = None

    @property
    def failure_tol(self) -> int:
        """Steps without improvement before the box shrinks: max(4, d) designs' worth."""
        return math.ceil(max(4.0 / self.batch, self.dim / self.batch))

    @property
    def collapsed(self) -> bool:
        """Whether the box has shrunk below its minimum (time to restart elsewhere)."""
        return self.length < self.length_min

    def box(self, centre: np.ndarray, log_ell: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners of the box around ``centre``, each edge scaled by the variable's length-scale
        relative to their geometric mean (the box's volume is length^d)."""
        ell = np.exp(log_ell - np.mean(log_ell))
        half = 0.5 * self.length * np.clip(ell, 0.05, 20.0)
        if self.floor is not None:
            half = np.maximum(half, self.floor)
        return np.clip(centre - half, 0.0, 1.0), np.clip(centre + half, 0.0, 1.0)

    def update(self, improved: bool) -> None:
        """Count a step; double the box after ``success_tol`` improving steps, halve it after ``failure_tol``
        others."""
        if improved:
            self.successes, self.failures = self.successes + 1, 0
        else:
            self.successes, self.failures = 0, self.failures + 1
        if self.successes >= self.success_tol:
            self.length, self.successes = min(2.0 * self.length, self.length_max), 0
        elif self.failures >= self.failure_tol:
            self.length, self.failures = self.length / 2.0, 0

    def restart(self) -> None:
        """A fresh box of the initial size (the caller moves its centre)."""
        self.length, self.successes, self.failures = 0.8, 0, 0
