"""Static load on the rocker, M_r(ψ): the torque about C needed to hold the rocker at ψ (bag, gravity), N·m.

Stored as a piecewise cubic (breakpoints in rad, coefficients per interval) so the numba kernels evaluate the very
same function as Python code.  By virtual work the motor of any design sees T_l = M_r(ψ) · dψ/dθ.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit
from scipy.interpolate import CubicSpline

from mechopt.errors import InputError


@njit(cache=True)
def _load_at(breaks, coefs, psi):
    """Piecewise-cubic value at ψ; the end pieces extend beyond the table (extrapolation)."""
    n = breaks.size - 1
    k = np.searchsorted(breaks, psi) - 1
    if k < 0:
        k = 0
    elif k > n - 1:
        k = n - 1
    dx = psi - breaks[k]
    return ((coefs[0, k] * dx + coefs[1, k]) * dx + coefs[2, k]) * dx + coefs[3, k]


@dataclass(frozen=True)
class RockerLoad:
    """Static rocker load M_r(ψ) as a piecewise cubic.

    Parameters
    ----------
    breaks : (n + 1,) ndarray
        Increasing breakpoints ψ (rad).
    coefs : (4, n) ndarray
        Cubic coefficients of each interval, highest power first (scipy's PPoly layout), N·m.
    """

    breaks: np.ndarray
    coefs: np.ndarray = field(repr=False)

    @classmethod
    def from_table(cls, psi: np.ndarray, torque: np.ndarray) -> RockerLoad:
        """Interpolate a table of ψ (rad) against M_r (N·m) by a not-a-knot cubic spline.

        Raises
        ------
        InputError
            If the table has fewer than 4 finite rows or repeated angles.
        """
        psi = np.asarray(psi, dtype=float)
        torque = np.asarray(torque, dtype=float)
        if psi.shape != torque.shape or psi.ndim != 1 or psi.size < 4:
            raise InputError(f"a load table needs at least 4 rows of (ψ, M_r), got shape {psi.shape}")
        if not (np.all(np.isfinite(psi)) and np.all(np.isfinite(torque))):
            raise InputError("the load table has non-finite values")
        order = np.argsort(psi)
        psi, torque = psi[order], torque[order]
        if np.any(np.diff(psi) <= 0):
            raise InputError("the load table repeats an angle ψ")
        spline = CubicSpline(psi, torque)
        return cls(np.ascontiguousarray(spline.x), np.ascontiguousarray(spline.c))

    @classmethod
    def constant(cls, torque: float) -> RockerLoad:
        """A load independent of ψ (N·m); zero gives a purely inertial mechanism."""
        coefs = np.zeros((4, 1))
        coefs[3, 0] = float(torque)
        return cls(np.array([-np.pi, np.pi]), coefs)

    def __call__(self, psi: np.ndarray | float) -> np.ndarray:
        """M_r at angles ψ (rad), N·m."""
        psi = np.asarray(psi, dtype=float)
        flat = np.array([_load_at(self.breaks, self.coefs, p) for p in psi.ravel()])
        return flat.reshape(psi.shape)
