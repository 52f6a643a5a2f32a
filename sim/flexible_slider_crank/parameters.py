"""The flexible slider-crank of paper 004: every physical and numerical setting of one simulation, in SI units.

The mechanism is in-line: the rigid crank O-A (length ``l2``) turns about O at the constant rate ``omega`` from
θ2 = 0 at t = 0; the flexible connecting rod A-B (length ``l3``, rectangular section ``a`` × ``h``, ``h`` in the
plane of motion) is pinned to the crank at A and to the slider (mass ``slider_mass``) at B, which runs on the x axis
through O.  No gravity (the paper lists none; the mechanism works in a horizontal plane).

Damping is material (Kelvin-Voigt, stiffness-proportional): stress = E (ε + ``beta`` ε̇), so a mode of circular
frequency ω_k has the damping ratio ζ_k = ``beta`` ω_k / 2.  The paper's Eq. 11 leaves ζ_k open; a single material
constant keeps both engines on the same damping (Exudyn's cable takes it as bending and axial damping β·EI, β·EA).

Initial state (the paper leaves it open too): at t = 0 the rod is straight in bending and moves with the rigid-body
velocity field of the mechanism at θ2 = 0; its axial strain is the quasi-static one of that instant (the modal
engine has no axial degrees of freedom, the Exudyn engine starts from it so that the slider is not released with
an unstrained rod).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any

from mechopt.errors import InputError

__all__ = ["MM", "FlexibleSliderCrank"]

#: Metres per millimetre: the one place where user-facing mm become SI.
MM = 1e-3


@dataclass(frozen=True)
class FlexibleSliderCrank:
    """One flexible slider-crank and how to simulate it (SI units throughout).

    Attributes
    ----------
    l2, l3 : float
        Crank and connecting-rod lengths (m).
    h, a : float
        Rod section: thickness in the plane of motion and width (m).
    E, rho : float
        Rod Young's modulus (Pa) and density (kg/m³).
    slider_mass : float
        Slider mass (kg).
    omega : float
        Crank rate (rad/s), constant.
    beta : float
        Material damping time constant (s): ζ_k = beta ω_k / 2.
    t_end : float
        Simulated time (s), responses sampled on ``n_samples`` equally spaced instants from 0 to ``t_end``.
    n_samples : int
        Number of samples (the paper's 121).
    n_elements : int
        Beam elements of the rod (both engines).
    n_modes : int
        Bending modes kept by the modal engine.
    axial_stiffening : bool
        Modal engine only: add the geometric stiffness of the rod's quasi-static axial force (not in the paper's
        linear model; the Exudyn cable has it by construction).
    """

    l2: float = 50.0 * MM
    l3: float = 350.0 * MM
    h: float = 1.53075 * MM
    a: float = 25.0 * MM
    E: float = 7.1e10
    rho: float = 2660.0
    slider_mass: float = 0.245
    omega: float = 26.19
    beta: float = 5.0e-4
    t_end: float = 0.48
    n_samples: int = 121
    n_elements: int = 8
    n_modes: int = 4
    axial_stiffening: bool = False

    def __post_init__(self) -> None:
        for key in ("l2", "l3", "h", "a", "E", "rho", "slider_mass", "omega", "t_end"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value <= 0:
                raise InputError(f"flexible slider-crank: {key} = {value!r}; expected a finite number > 0")
        if not (isinstance(self.beta, int | float) and math.isfinite(self.beta) and self.beta >= 0):
            raise InputError(f"flexible slider-crank: beta = {self.beta!r}; expected a finite number >= 0 (s)")
        if not self.l3 > self.l2:
            raise InputError(f"flexible slider-crank: rod l3 = {self.l3 / MM:g} mm must be longer than the crank "
                             f"l2 = {self.l2 / MM:g} mm for the slider to follow a full crank turn")
        for key, low in (("n_samples", 2), ("n_elements", 2), ("n_modes", 1)):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise InputError(f"flexible slider-crank: {key} = {value!r}; expected a whole number >= {low}")
        if self.n_modes > 2 * self.n_elements:
            raise InputError(f"flexible slider-crank: n_modes = {self.n_modes} exceeds the "
                             f"{2 * self.n_elements} bending degrees of freedom of {self.n_elements} elements")

    @classmethod
    def from_mm(cls, l2_mm: float, l3_mm: float, h_mm: float, a_mm: float = 25.0, **kwargs: Any) -> FlexibleSliderCrank:
        """Build from lengths in mm (the user-facing unit); other keywords in SI as in the attributes."""
        return cls(l2=l2_mm * MM, l3=l3_mm * MM, h=h_mm * MM, a=a_mm * MM, **kwargs)

    def with_(self, **changes: Any) -> FlexibleSliderCrank:
        """A copy with some attributes changed."""
        return replace(self, **changes)

    @property
    def area(self) -> float:
        """Section area a·h (m²)."""
        return self.a * self.h

    @property
    def second_moment(self) -> float:
        """Second moment of area about the bending axis, a h³ / 12 (m⁴)."""
        return self.a * self.h**3 / 12.0

    @property
    def kappa(self) -> float:
        """E h² / ρ (m⁴/s²): with the rod's length, the only material/section group the linear bending sees."""
        return self.E * self.h**2 / self.rho

    def as_dict(self) -> dict[str, Any]:
        """All attributes, JSON-able."""
        return asdict(self)
