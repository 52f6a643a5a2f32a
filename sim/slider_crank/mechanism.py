"""The slider-crank of a dynamics study: everything but the design lengths (r, l, h).

A design is the triple (crank r, rod l, offset h) in mm; :class:`SliderCrank` holds what stays fixed while it
varies: the inertias and masses, the loads on the slider, the crank motion, the assembly branch and the
transmission-angle limits.  Lengths in mm at this surface, inertias in kg·m², masses in kg, forces in N.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechopt.errors import InputError
from mechopt.sim.slider_crank.kinematics import BRANCH_RIGHT, check_branch
from mechopt.sim.slider_crank.motion import CrankMotion


@dataclass(frozen=True)
class SliderCrank:
    """Fixed part of a slider-crank driven at O with a prescribed crank motion θ(t).

    Parameters
    ----------
    motion : CrankMotion
        Prescribed θ(t) over one revolution.
    j0 : float
        Inertia on the crank about O: motor and crank (kg·m²); the crank's centre of mass is at O.
    rod_mass : float
        Mass of the rod AB (kg).
    rod_inertia : float or None
        Rod's moment of inertia about its centre of mass (kg·m²); None for a uniform bar, m l²/12.
    rod_com : float
        Centre of mass of the rod as a fraction of |AB| from A (0.5 for a uniform bar).
    slider_mass : float
        Mass of the slider B (kg).
    spring_k : float
        Stiffness of a spring on the slider (N/mm), pushing it back towards ``spring_free_mm``.
    spring_free_mm : float
        Slider position x at which the spring is relaxed (mm).
    force : float
        Constant external force on the slider along +x (N).
    gravity : float
        Gravitational acceleration along −y (m/s²), acting on the rod (the crank's mass is at O, the slider's
        weight is carried by its guide).
    branch : int
        +1: slider on the +x side of the crank pin; −1: on the −x side.
    ta_limits_deg : (float, float)
        Allowed range of the transmission angle TA = 90° + asin((h − r sin θ)/l) over the motion (deg).
    """

    motion: CrankMotion
    j0: float = 0.0
    rod_mass: float = 0.0
    rod_inertia: float | None = None
    rod_com: float = 0.5
    slider_mass: float = 0.0
    spring_k: float = 0.0
    spring_free_mm: float = 0.0
    force: float = 0.0
    gravity: float = 0.0
    branch: int = BRANCH_RIGHT
    ta_limits_deg: tuple[float, float] = (45.0, 135.0)

    def __post_init__(self) -> None:
        for name in ("j0", "rod_mass", "slider_mass", "spring_k"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0:
                raise InputError(f"{name} = {value!r}: expected a finite value >= 0")
        if self.rod_inertia is not None and not (np.isfinite(self.rod_inertia) and self.rod_inertia >= 0):
            raise InputError(f"rod_inertia = {self.rod_inertia!r} kg·m²: expected a finite value >= 0 or None")
        if not 0.0 <= self.rod_com <= 1.0:
            raise InputError(f"rod_com = {self.rod_com!r}: expected a fraction of |AB| in [0, 1]")
        for name in ("spring_free_mm", "force", "gravity"):
            if not np.isfinite(getattr(self, name)):
                raise InputError(f"{name} = {getattr(self, name)!r}: expected a finite number")
        check_branch(self.branch)
        lo, hi = (float(v) for v in self.ta_limits_deg)
        if not 0.0 <= lo < 90.0 < hi <= 180.0:
            raise InputError(f"ta_limits_deg = {self.ta_limits_deg!r}: expected 0 <= lower < 90 < upper <= 180")
        object.__setattr__(self, "ta_limits_deg", (lo, hi))

    def rod_inertia_si(self, l_m: float) -> float:
        """Rod inertia about its centre of mass (kg·m²) for a rod of length ``l_m`` (m)."""
        return self.rod_mass * l_m * l_m / 12.0 if self.rod_inertia is None else float(self.rod_inertia)
