"""Prescribed output motion ψ(t): rest-to-rest laws, reciprocating between ψ_start and ψ_end.

The ventilator's beam moves ψ_start → ψ_end with the quintic law s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ in one stroke time and
back the same way (one reciprocating cycle, no dwell).  Angles in rad, times in s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from mechopt.errors import InputError

#: Law codes shared with the numba kernels (a string cannot cross into nopython code cheaply).
LAW_CODES = {"quintic": 0, "cycloidal": 1}


@njit(cache=True)
def _law(code: int, x: float) -> tuple[float, float, float]:
    """Normalised rest-to-rest law s(x), s'(x), s''(x) on x ∈ [0, 1]."""
    if code == 0:
        s = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
        ds = 30.0 * x * x * (1.0 - x) * (1.0 - x)
        dds = 60.0 * x * (1.0 - x) * (1.0 - 2.0 * x)
    else:
        two_pi = 2.0 * np.pi
        s = x - np.sin(two_pi * x) / two_pi
        ds = 1.0 - np.cos(two_pi * x)
        dds = two_pi * np.sin(two_pi * x)
    return s, ds, dds


@njit(cache=True)
def _psi_at(code: int, psi_start: float, psi_end: float, t_stroke: float, t: float) -> tuple[float, float, float]:
    """ψ, ψ̇, ψ̈ of the reciprocating cycle at time t (periodic with period 2·t_stroke)."""
    period = 2.0 * t_stroke
    t = t - period * np.floor(t / period)
    amp = psi_end - psi_start
    if t <= t_stroke:
        s, ds, dds = _law(code, t / t_stroke)
        return psi_start + amp * s, amp * ds / t_stroke, amp * dds / (t_stroke * t_stroke)
    # The return stroke is the forward stroke played backwards: same ψ̈, opposite ψ̇.
    s, ds, dds = _law(code, (period - t) / t_stroke)
    return psi_start + amp * s, -amp * ds / t_stroke, amp * dds / (t_stroke * t_stroke)


@dataclass(frozen=True)
class MotionLaw:
    """A reciprocating rest-to-rest motion of the output link.

    Parameters
    ----------
    psi_start, psi_end : float
        Output angles at the start and end of the stroke (rad).
    t_stroke : float
        Duration of one stroke (s); the cycle (there and back) lasts ``2 * t_stroke``.
    law : str
        ``"quintic"`` (s = 10τ³ − 15τ⁴ + 6τ⁵) or ``"cycloidal"`` (s = τ − sin(2πτ)/2π).
    """

    psi_start: float
    psi_end: float
    t_stroke: float
    law: str = "quintic"

    def __post_init__(self) -> None:
        if self.law not in LAW_CODES:
            raise InputError(f"unknown motion law {self.law!r}; expected one of {sorted(LAW_CODES)}")
        if not (np.isfinite(self.t_stroke) and self.t_stroke > 0):
            raise InputError(f"stroke time {self.t_stroke!r} s is not a positive number")
        if not (np.isfinite(self.psi_start) and np.isfinite(self.psi_end)) or self.psi_start == self.psi_end:
            raise InputError(
                f"stroke ψ_start={self.psi_start!r} rad → ψ_end={self.psi_end!r} rad must be two distinct finite angles"
            )

    @property
    def code(self) -> int:
        """Integer code of the law for the numba kernels."""
        return LAW_CODES[self.law]

    @property
    def period(self) -> float:
        """Duration of one reciprocating cycle (s)."""
        return 2.0 * self.t_stroke

    def __call__(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Evaluate ψ(t), ψ̇(t), ψ̈(t).

        Parameters
        ----------
        t : array_like
            Times (s); the law is periodic with period ``2 * t_stroke``.

        Returns
        -------
        psi, psi_dot, psi_ddot : ndarray
            Angle (rad), angular velocity (rad/s) and acceleration (rad/s²).
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.empty((3, t.size))
        _psi_many(self.code, self.psi_start, self.psi_end, self.t_stroke, t.ravel(), out)
        return out[0].reshape(t.shape), out[1].reshape(t.shape), out[2].reshape(t.shape)

    def time_grid(self, n_intervals: int) -> np.ndarray:
        """Uniform grid of ``n_intervals + 1`` times over one cycle, end points included (s)."""
        return np.linspace(0.0, self.period, int(n_intervals) + 1)


@njit(cache=True)
def _psi_many(code, psi_start, psi_end, t_stroke, t, out):
    for i in range(t.size):
        out[0, i], out[1, i], out[2, i] = _psi_at(code, psi_start, psi_end, t_stroke, t[i])
