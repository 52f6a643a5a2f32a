"""The result of simulating one slider-crank design: the signed motor torque over a revolution, RMS and peak."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class SliderCrankResult:
    """Motor torque a design needs to follow the prescribed crank motion.

    Attributes
    ----------
    design : (3,) ndarray
        r, l, h (mm).
    engine : str
        ``"analytic"`` or ``"pymunk"``.
    t, tau, theta, x : (n,) ndarray
        Times (s), signed motor torque (N·m, positive along increasing θ), crank angle (rad), slider position (mm).
    t_rms, t_max : float
        RMS of τ over the cycle (trapezoid) and max |τ| (N·m).
    margins : dict
        Constraint margins (mm, deg).
    dt : float
        Step (s) of the pymunk engine, or the grid spacing of the analytic one.
    wall_time_s : float
        Wall-clock time (s).
    """

    design: np.ndarray
    engine: str
    t: np.ndarray
    tau: np.ndarray
    theta: np.ndarray
    x: np.ndarray
    t_rms: float
    t_max: float
    margins: dict
    dt: float
    wall_time_s: float

    def summary(self) -> dict:
        """JSON-able summary (no time series)."""
        r, l, h = (float(v) for v in self.design)
        return {"design_mm": {"r": r, "l": l, "h": h}, "engine": self.engine, "margins": self.margins,
                "t_rms_Nm": float(self.t_rms), "t_max_Nm": float(self.t_max), "dt_s": float(self.dt),
                "n_samples": int(self.t.size), "wall_time_s": float(self.wall_time_s)}
