"""The four-bar mechanism of a study: everything but the three design lengths.

A design is the triple (|OA|, |AB|, |BC|) in mm; :class:`FourBar` holds what stays fixed while the designer varies
it: the rocker pivot C, the inertias, the static load on the rocker, the prescribed output motion, the assembly
branch and the toggle margin.  Lengths in mm, inertias in kg·m², masses in kg, angles in rad.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechopt.errors import InputError
from mechopt.sim.four_bar.kinematics import BRANCH_SUBTRACT, validate_pivot
from mechopt.sim.four_bar.load import RockerLoad
from mechopt.sim.four_bar.motion import MotionLaw


@dataclass(frozen=True)
class FourBar:
    """Fixed part of a four-bar O-A-B-C driven at O with a prescribed rocker motion ψ(t).

    Parameters
    ----------
    pivot_c : (float, float)
        Rocker ground pivot C (mm), O at the origin.
    j0 : float
        Inertia on the crank about O: motor, gearbox and crank (kg·m²).
    i_r : float
        Inertia of rocker and everything it carries, about C (kg·m²).
    motion : MotionLaw
        Prescribed ψ(t) over one reciprocating cycle.
    load : RockerLoad
        Static rocker load M_r(ψ) (N·m), positive when the motor must push ψ up to hold it.
    coupler_mass : float
        Mass of the coupler AB (kg), modelled as a uniform bar; 0 for a light coupler.
    branch : int
        Assembly branch of Eq. 4 (−1: θ1, arccos subtracted).
    toggle_margin_deg : float
        ζ_min: the crank–coupler angle at A must stay in [ζ_min, 180° − ζ_min] over the stroke (deg).
    """

    pivot_c: tuple[float, float]
    j0: float
    i_r: float
    motion: MotionLaw
    load: RockerLoad
    coupler_mass: float = 0.0
    branch: int = BRANCH_SUBTRACT
    toggle_margin_deg: float = 15.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "pivot_c", validate_pivot(self.pivot_c))
        for name in ("j0", "i_r", "coupler_mass"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0:
                raise InputError(f"{name} = {value!r}: expected a finite value >= 0")
        if self.j0 + self.i_r <= 0:
            raise InputError("j0 and i_r are both zero: the mechanism has no inertia")
        if self.branch not in (-1, 1):
            raise InputError(f"branch = {self.branch!r}: expected -1 (θ1) or +1 (θ2)")
        if not 0.0 <= self.toggle_margin_deg < 90.0:
            raise InputError(f"toggle margin {self.toggle_margin_deg!r}°: expected a value in [0°, 90°)")

    @property
    def psi_start(self) -> float:
        """Output angle at the start of the stroke (rad)."""
        return self.motion.psi_start

    @property
    def psi_end(self) -> float:
        """Output angle at the end of the stroke (rad)."""
        return self.motion.psi_end
