"""Prescribed crank motion θ(t) over one revolution: constant speed, or a speed that fluctuates once per turn.

θ(t) = θ0 + ω t + a sin(ω t), θ̇ = ω (1 + a cos ω t), θ̈ = −a ω² sin ω t, with |a| < 1 so the crank keeps turning
the same way; a = 0 is the constant speed of papers 001 and 003.  One cycle lasts T = 2π/ω and turns the crank once.
Angles in rad, times in s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechopt.errors import InputError


@dataclass(frozen=True)
class CrankMotion:
    """Crank motion over one revolution.

    Parameters
    ----------
    omega : float
        Mean crank speed ω (rad/s), > 0 (counter-clockwise).
    theta0 : float
        Crank angle at t = 0 (rad).
    fluctuation : float
        a in θ(t) = θ0 + ω t + a sin(ω t), |a| < 1 (rad); 0 for constant speed.
    """

    omega: float
    theta0: float = 0.0
    fluctuation: float = 0.0

    def __post_init__(self) -> None:
        if not np.isfinite(self.omega) or self.omega <= 0:
            raise InputError(f"crank speed ω = {self.omega!r} rad/s: expected a finite value > 0")
        if not np.isfinite(self.theta0):
            raise InputError(f"start angle θ0 = {self.theta0!r} rad: expected a finite number")
        if not (np.isfinite(self.fluctuation) and abs(self.fluctuation) < 1.0):
            raise InputError(f"speed fluctuation a = {self.fluctuation!r}: expected |a| < 1 (crank keeps turning)")

    @classmethod
    def from_rpm(cls, rpm: float, theta0_deg: float = 0.0, fluctuation: float = 0.0) -> CrankMotion:
        """A motion from a speed in rev/min and a start angle in degrees."""
        return cls(float(rpm) * np.pi / 30.0, float(np.radians(theta0_deg)), float(fluctuation))

    @property
    def period(self) -> float:
        """Duration of one revolution T = 2π/ω (s)."""
        return 2.0 * np.pi / self.omega

    def time_grid(self, n_intervals: int) -> np.ndarray:
        """``n_intervals + 1`` uniform times over one cycle, both ends included (s)."""
        if int(n_intervals) < 2:
            raise InputError(f"n_intervals = {n_intervals!r}: expected at least 2")
        return np.linspace(0.0, self.period, int(n_intervals) + 1)

    def __call__(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """θ (rad), θ̇ (rad/s), θ̈ (rad/s²) at times ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        wt = self.omega * t
        a = self.fluctuation
        theta = self.theta0 + wt + a * np.sin(wt)
        return theta, self.omega * (1.0 + a * np.cos(wt)), -a * self.omega**2 * np.sin(wt)
