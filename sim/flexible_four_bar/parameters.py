"""The flexible four-bar of paper 004 (Section 3.2): every physical and numerical setting of one simulation, in SI.

Frame O2 = (0, 0), O4 = (l1, 0).  The crank O2-B (length ``l2``) is rigid and turns about O2 at the constant rate
``omega`` from θ2 = 0 at t = 0 (counter-clockwise).  The coupler B-C (``l3``) and the follower O4-C (``l4``) are
flexible, each with its own material and rectangular section (:class:`FlexibleLink`), pinned at B, C and O4.  The
assembly branch is the one with C above the frame line at t = 0 (``branch`` = +1; the paper's Figure 3b is not in
its text).  No gravity (the paper lists none; the mechanism works in a horizontal plane, as its slider-crank).

Damping is material (Kelvin-Voigt, stiffness-proportional), as in the slider-crank case: stress = E (ε + ``beta``
ε̇), so a mode of circular frequency ω_k has the damping ratio ζ_k = ``beta`` ω_k / 2 (the paper's Eq. 11 leaves ζ_k
open).  Initial state (also open): the links start straight, moving with the rigid-body velocity field at θ2 = 0.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any

from mechopt.errors import InputError

__all__ = ["MM", "FlexibleFourBar", "FlexibleLink"]

#: Metres per millimetre: the one place where user-facing mm become SI.
MM = 1e-3


def _positive(owner: str, obj: Any, keys: tuple[str, ...]) -> None:
    for key in keys:
        value = getattr(obj, key)
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value <= 0:
            raise InputError(f"{owner}: {key} = {value!r}; expected a finite number > 0")


@dataclass(frozen=True)
class FlexibleLink:
    """Material and rectangular section of one flexible link (SI).

    Attributes
    ----------
    E, rho : float
        Young's modulus (Pa) and density (kg/m³).
    h, a : float
        Thickness in the plane of motion (bending) and width (m).
    """

    E: float = 7.1e10
    rho: float = 2660.0
    h: float = 1.53075 * MM
    a: float = 23.518 * MM

    def __post_init__(self) -> None:
        _positive("flexible link", self, ("E", "rho", "h", "a"))

    @property
    def area(self) -> float:
        """Section area a·h (m²)."""
        return self.a * self.h

    @property
    def second_moment(self) -> float:
        """Second moment of area about the bending axis, a h³ / 12 (m⁴)."""
        return self.a * self.h**3 / 12.0

    @property
    def mass_per_length(self) -> float:
        """ρA (kg/m)."""
        return self.rho * self.area

    @property
    def bending_stiffness(self) -> float:
        """EI (N m²)."""
        return self.E * self.second_moment

    @property
    def kappa(self) -> float:
        """E h² / ρ (m⁴/s²): with the length, the only material/section group the linear bending sees."""
        return self.E * self.h**2 / self.rho


@dataclass(frozen=True)
class FlexibleFourBar:
    """One flexible four-bar and how to simulate it (SI units throughout).

    Attributes
    ----------
    l1, l2, l3, l4 : float
        Frame |O2 O4|, crank |O2 B|, coupler |BC| and follower |O4 C| lengths (m).
    coupler, follower : FlexibleLink
        Material and section of the coupler (link 3) and the follower (link 4).
    omega : float
        Crank rate (rad/s), constant; θ2 = ω t.
    beta : float
        Material damping time constant (s): ζ_k = beta ω_k / 2.
    t_end : float
        Simulated time (s); responses sampled on ``n_samples`` equally spaced instants from 0 to ``t_end``.
    n_samples : int
        Number of samples (the paper's 121).
    n_elements : int
        Beam elements per flexible link (both engines; Exudyn needs an even number for a mid-span node).
    n_modes : int
        Bending modes per link kept by the modal engine (3: the fourth is antisymmetric and leaves the mid-span
        deflection unchanged; 3 modes and 8 elements agree with 8 modes and 16 elements to 2e-4 of its range).
    geometric_stiffness : bool
        Modal engine only: add the geometric stiffness of each link's axial force, the centrifugal softening of its
        rotating frame and the turn of the chords as the bending shortens them (not in the paper's linear model;
        Exudyn's geometrically exact cable has them by construction).
    branch : int
        +1: C on the left of the diagonal B → O4 (above the frame at t = 0); −1 the other assembly.
    """

    l1: float = 285.0 * MM
    l2: float = 100.0 * MM
    l3: float = 250.0 * MM
    l4: float = 250.0 * MM
    coupler: FlexibleLink = FlexibleLink()
    follower: FlexibleLink = FlexibleLink()
    omega: float = 26.18
    beta: float = 5.0e-4
    t_end: float = 0.48
    n_samples: int = 121
    n_elements: int = 8
    n_modes: int = 3
    geometric_stiffness: bool = False
    branch: int = 1

    def __post_init__(self) -> None:
        _positive("flexible four-bar", self, ("l1", "l2", "l3", "l4", "omega", "t_end"))
        if not (isinstance(self.beta, int | float) and math.isfinite(self.beta) and self.beta >= 0):
            raise InputError(f"flexible four-bar: beta = {self.beta!r}; expected a finite number >= 0 (s)")
        for key, low in (("n_samples", 2), ("n_elements", 2), ("n_modes", 1)):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise InputError(f"flexible four-bar: {key} = {value!r}; expected a whole number >= {low}")
        if self.n_modes > 2 * self.n_elements:
            raise InputError(f"flexible four-bar: n_modes = {self.n_modes} exceeds the {2 * self.n_elements} "
                             f"bending degrees of freedom of {self.n_elements} elements")
        if self.branch not in (1, -1):
            raise InputError(f"flexible four-bar: branch = {self.branch!r}; expected +1 or -1")
        if not all(isinstance(k, FlexibleLink) for k in (self.coupler, self.follower)):
            raise InputError("flexible four-bar: coupler and follower must be FlexibleLink")

    @classmethod
    def from_mm(cls, l1: float, l2: float, l3: float, l4: float, h3: float = 1.53075, a3: float = 23.518,
                h4: float = 1.53075, a4: float = 23.518, E3: float = 7.1e10, rho3: float = 2660.0,
                E4: float = 7.1e10, rho4: float = 2660.0, **kwargs: Any) -> FlexibleFourBar:
        """Build from lengths and sections in mm (the user-facing unit), E in Pa and ρ in kg/m³; other keywords in
        SI as in the attributes."""
        return cls(l1=l1 * MM, l2=l2 * MM, l3=l3 * MM, l4=l4 * MM,
                   coupler=FlexibleLink(E=E3, rho=rho3, h=h3 * MM, a=a3 * MM),
                   follower=FlexibleLink(E=E4, rho=rho4, h=h4 * MM, a=a4 * MM), **kwargs)

    def with_(self, **changes: Any) -> FlexibleFourBar:
        """A copy with some attributes changed."""
        return replace(self, **changes)

    @property
    def lengths(self) -> tuple[float, float, float, float]:
        """(l1, l2, l3, l4) in m."""
        return self.l1, self.l2, self.l3, self.l4

    def as_dict(self) -> dict[str, Any]:
        """All attributes, JSON-able."""
        return asdict(self)
