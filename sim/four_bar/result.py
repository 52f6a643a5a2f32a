"""The result of simulating one design: the signed motor torque over a cycle and its RMS and peak."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def rms_over_cycle(t: np.ndarray, tau: np.ndarray) -> float:
    """T_RMS = sqrt of the time average of τ² over the cycle, by the trapezoid rule on the time grid (N·m).

    Parameters
    ----------
    t : (n,) ndarray
        Increasing times covering one cycle, end points included (s).
    tau : (n,) ndarray
        Motor torque at those times (N·m).
    """
    t = np.asarray(t, dtype=float)
    tau = np.asarray(tau, dtype=float)
    return float(np.sqrt(np.trapezoid(tau * tau, t) / (t[-1] - t[0])))


@dataclass
class SimulationResult:
    """Motor torque needed by one design to follow the prescribed motion.

    Attributes
    ----------
    design : (3,) ndarray
        |OA|, |AB|, |BC| (mm).
    engine : str
        ``"pymunk"`` or ``"analytic"``.
    t : (n,) ndarray
        Times over one cycle (s).
    tau : (n,) ndarray
        Signed motor torque (N·m), positive in the sense of increasing θ.
    theta, psi : (n,) ndarray
        Crank and rocker angles (rad).
    t_rms, t_max : float
        RMS of τ over the cycle and max |τ| (N·m).
    margins : dict
        Constraint margins of the design (mm or deg).
    feasible : bool
        All constraints satisfied (toggle margin included).
    message : str
        One-line feasibility summary.
    dt : float
        Integration step (s) for pymunk; the grid spacing for the analytic engine.
    wall_time_s : float
        Wall-clock time of the simulation (s).
    """

    design: np.ndarray
    engine: str
    t: np.ndarray
    tau: np.ndarray
    theta: np.ndarray
    psi: np.ndarray
    t_rms: float
    t_max: float
    margins: dict = field(default_factory=dict)
    feasible: bool = True
    message: str = ""
    dt: float = float("nan")
    wall_time_s: float = float("nan")

    def summary(self) -> dict:
        """JSON-able summary (no time series)."""
        return {
            "design_mm": {"oa": float(self.design[0]), "ab": float(self.design[1]), "bc": float(self.design[2])},
            "engine": self.engine,
            "feasible": bool(self.feasible),
            "message": self.message,
            "margins": self.margins,
            "t_rms_Nm": float(self.t_rms),
            "t_max_Nm": float(self.t_max),
            "dt_s": float(self.dt),
            "n_samples": int(self.t.size),
            "wall_time_s": float(self.wall_time_s),
        }
