"""Feasibility of four-bar designs for a prescribed stroke ψ_start → ψ_end, with margins.

Constraints (paper Section 3, plus the toggle margin every designer applies):

* **assembly at ψ_start and ψ_end** (Eq. 7): the triangle O-A-B closes, |OA − AB| <= |OB(ψ)| <= |OA| + |AB|.
  Margin: the distance (mm) of |OB| to the nearer bound, positive inside.
* **assembly along the stroke**: the same at every ψ in between (|OB(ψ)| has one maximum and one minimum per
  turn, at ψ = atan2(y_C, x_C) and that + π; both are checked exactly when they fall inside the stroke).
* **monotonic crank** (the dynamic constraint, Eq. 8, checked along the stroke so that an even number of branch or
  circuit defects is caught too): θ'(ψ) ∝ sin μ keeps its sign, μ being the angle at B between B→C and B→A.
  Margin: the smallest of μ and 180° − μ on the starting side (deg), negative once μ has changed side.
* **toggle margin**: the crank–coupler angle ζ at A stays within [ζ_min, 180° − ζ_min] (deg).

All of it is vectorised over many designs (numba, parallel) for plots, brute force and the surrogate's search.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit, prange

from mechopt.errors import InfeasibleDesignError, InputError
from mechopt.sim.four_bar.kinematics import _crank_kernel
from mechopt.sim.four_bar.mechanism import FourBar

#: ψ samples along the stroke at which the along-stroke constraints are checked.
N_CHECK = 241

MARGIN_NAMES = ("assembly_start_mm", "assembly_end_mm", "assembly_stroke_mm", "monotonic_deg", "toggle_deg")


@njit(cache=True)
def _assembly_margin(oa, ab, xc, yc, bc, psi):
    xb = xc + bc * np.cos(psi)
    yb = yc + bc * np.sin(psi)
    ob = np.sqrt(xb * xb + yb * yb)
    return min(oa + ab - ob, ob - abs(oa - ab))


@njit(cache=True)
def _design_margins(oa, ab, bc, xc, yc, psi_start, psi_end, branch, zeta_min, cpsi, spsi, out):
    out[0] = _assembly_margin(oa, ab, xc, yc, bc, psi_start)
    out[1] = _assembly_margin(oa, ab, xc, yc, bc, psi_end)
    lo = min(psi_start, psi_end)
    hi = max(psi_start, psi_end)
    stroke = min(out[0], out[1])
    # |OB(ψ)| is extremal where B lies on the line OC: check those angles exactly when inside the stroke.
    base = np.arctan2(yc, xc)
    for extra in (base, base + np.pi):
        e = lo + ((extra - lo) % (2.0 * np.pi))
        if e <= hi:
            stroke = min(stroke, _assembly_margin(oa, ab, xc, yc, bc, e))
    # Track sin μ (monotonic) and |cos ζ| (toggle) and take one arcsin at the end: min(μ, π − μ) = asin(sin μ)
    # on the starting side, and min(ζ − ζ_min, π − ζ_min − ζ) = π/2 − ζ_min − asin|cos ζ|.
    side = 0.0
    min_sin_mu = np.inf
    max_cos_zeta = 0.0
    for k in range(cpsi.size):
        xb = xc + bc * cpsi[k]
        yb = yc + bc * spsi[k]
        ob = np.sqrt(xb * xb + yb * yb)
        m = min(oa + ab - ob, ob - abs(oa - ab))
        if m < stroke:
            stroke = m
        ok, ax, ay, t1, t2 = _crank_kernel(oa, ab, bc, xc, yc, cpsi[k], spsi[k], branch)
        if not ok:
            continue
        # μ: angle at B from B→C to B→A; ζ: angle at A between A→O and A→B.
        sin_mu = ((xc - xb) * (ay - yb) - (yc - yb) * (ax - xb)) / (bc * ab)
        if side == 0.0:
            side = 1.0 if sin_mu >= 0.0 else -1.0
        min_sin_mu = min(min_sin_mu, side * sin_mu)
        cos_zeta = abs(-ax * (xb - ax) - ay * (yb - ay)) / (oa * ab)
        max_cos_zeta = max(max_cos_zeta, cos_zeta)
    out[2] = stroke
    if side == 0.0:
        out[3] = np.nan
        out[4] = np.nan
    else:
        out[3] = np.degrees(np.arcsin(max(-1.0, min(1.0, min_sin_mu))))
        out[4] = np.degrees(0.5 * np.pi - zeta_min - np.arcsin(min(1.0, max_cos_zeta)))


@njit(cache=True, parallel=True)
def _margins_many(designs, xc, yc, psi_start, psi_end, branch, zeta_min, cpsi, spsi, out):
    for i in prange(designs.shape[0]):
        _design_margins(
            designs[i, 0], designs[i, 1], designs[i, 2], xc, yc, psi_start, psi_end, branch, zeta_min, cpsi, spsi,
            out[i],
        )


@njit(cache=True)
def _margins_few(designs, xc, yc, psi_start, psi_end, branch, zeta_min, cpsi, spsi, out):
    for i in range(designs.shape[0]):
        _design_margins(
            designs[i, 0], designs[i, 1], designs[i, 2], xc, yc, psi_start, psi_end, branch, zeta_min, cpsi, spsi,
            out[i],
        )


#: Below this many designs the margins run on one thread: waking numba's thread pool costs milliseconds on a busy
#: machine, a hundred times one design's work (an optimizer's finite differences ask for one design at a time).
_PARALLEL_FROM = 4096


@dataclass(frozen=True)
class FeasibilityReport:
    """Constraint margins of a batch of designs (positive = satisfied).

    Attributes
    ----------
    designs : (n, 3) ndarray
        The designs (|OA|, |AB|, |BC|) in mm.
    assembly_start_mm, assembly_end_mm : (n,) ndarray
        Assembly margins at ψ_start and ψ_end (mm), Eq. 7.
    assembly_stroke_mm : (n,) ndarray
        Smallest assembly margin over the whole stroke (mm).
    monotonic_deg : (n,) ndarray
        Margin of the monotonic-crank constraint (deg); NaN where the design never assembles.
    toggle_deg : (n,) ndarray
        Margin of the toggle constraint ζ ∈ [ζ_min, 180° − ζ_min] (deg).
    """

    designs: np.ndarray
    assembly_start_mm: np.ndarray
    assembly_end_mm: np.ndarray
    assembly_stroke_mm: np.ndarray
    monotonic_deg: np.ndarray
    toggle_deg: np.ndarray

    @property
    def movable(self) -> np.ndarray:
        """Designs that can be driven through the stroke: assemblable everywhere and the crank monotonic."""
        with np.errstate(invalid="ignore"):
            return (self.assembly_stroke_mm >= 0) & (self.monotonic_deg > 0)

    @property
    def feasible(self) -> np.ndarray:
        """Designs satisfying every constraint, the toggle margin included."""
        with np.errstate(invalid="ignore"):
            return self.movable & (self.toggle_deg >= 0)

    def margins(self, i: int = 0) -> dict[str, float]:
        """Margins of design ``i`` as a dict (mm or deg, see the attribute names)."""
        return {name: float(getattr(self, name)[i]) for name in MARGIN_NAMES}

    def message(self, i: int = 0) -> str:
        """One line saying whether design ``i`` is feasible, and else which constraint fails by how much."""
        m = self.margins(i)
        d = self.designs[i]
        head = f"design |OA|={d[0]:.3f} |AB|={d[1]:.3f} |BC|={d[2]:.3f} mm"
        failures = []
        if m["assembly_start_mm"] < 0:
            failures.append(f"not assemblable at ψ_start (short by {-m['assembly_start_mm']:.3f} mm)")
        if m["assembly_end_mm"] < 0:
            failures.append(f"not assemblable at ψ_end (short by {-m['assembly_end_mm']:.3f} mm)")
        if m["assembly_stroke_mm"] < 0 and m["assembly_start_mm"] >= 0 and m["assembly_end_mm"] >= 0:
            failures.append(f"not assemblable inside the stroke (short by {-m['assembly_stroke_mm']:.3f} mm)")
        if not m["monotonic_deg"] > 0 and np.isfinite(m["monotonic_deg"]):
            failures.append(f"crank not monotonic (branch/circuit defect, by {-m['monotonic_deg']:.2f}°)")
        if m["toggle_deg"] < 0:
            failures.append(f"toggle margin violated by {-m['toggle_deg']:.2f}°")
        if not failures:
            return (
                f"{head}: feasible (margins: assembly {m['assembly_stroke_mm']:.3f} mm, "
                f"monotonic {m['monotonic_deg']:.2f}°, toggle {m['toggle_deg']:.2f}°)"
            )
        return f"{head}: infeasible — " + "; ".join(failures)


def as_designs(designs: np.ndarray) -> np.ndarray:
    """Validate an (n, 3) array of designs in mm (finite, > 0) and return it as C-contiguous floats."""
    arr = np.ascontiguousarray(np.atleast_2d(np.asarray(designs, dtype=float)))
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"designs must be an (n, 3) array of |OA|, |AB|, |BC| in mm, got shape {arr.shape}")
    bad = ~np.isfinite(arr) | (arr <= 0)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        name = ("|OA|", "|AB|", "|BC|")[j]
        raise InputError(f"{name} = {arr[i, j]:g} mm in design {i}: expected a finite length > 0 mm")
    return arr


def check_feasibility(designs: np.ndarray, mechanism: FourBar, n_check: int = N_CHECK) -> FeasibilityReport:
    """Constraint margins of one or many designs.

    Parameters
    ----------
    designs : (3,) or (n, 3) array_like
        |OA|, |AB|, |BC| in mm.
    mechanism : FourBar
        Rocker pivot, stroke, branch and toggle margin.
    n_check : int
        ψ samples along the stroke for the along-stroke checks.

    Returns
    -------
    FeasibilityReport
        Margins per design; ``report.feasible`` is the boolean mask.
    """
    arr = as_designs(designs)
    out = np.empty((arr.shape[0], len(MARGIN_NAMES)))
    xc, yc = mechanism.pivot_c
    psi = np.linspace(mechanism.psi_start, mechanism.psi_end, int(n_check))
    kernel = _margins_many if arr.shape[0] >= _PARALLEL_FROM else _margins_few
    kernel(
        arr, xc, yc, mechanism.psi_start, mechanism.psi_end, mechanism.branch,
        np.radians(mechanism.toggle_margin_deg), np.cos(psi), np.sin(psi), out,
    )
    return FeasibilityReport(arr, *(out[:, k] for k in range(len(MARGIN_NAMES))))


def feasible_mask(designs: np.ndarray, mechanism: FourBar, n_check: int = N_CHECK) -> np.ndarray:
    """Boolean mask of the designs (n, 3) in mm that satisfy every constraint; invalid lengths are infeasible."""
    arr = np.ascontiguousarray(np.atleast_2d(np.asarray(designs, dtype=float)))
    valid = np.all(np.isfinite(arr) & (arr > 0), axis=1)
    mask = np.zeros(arr.shape[0], dtype=bool)
    if valid.any():
        mask[valid] = check_feasibility(arr[valid], mechanism, n_check).feasible
    return mask


def require_movable(design: np.ndarray, mechanism: FourBar) -> FeasibilityReport:
    """Feasibility report of one design; raise if it cannot be driven through the stroke at all.

    Raises
    ------
    InfeasibleDesignError
        If the design is not assemblable somewhere in the stroke or its crank is not monotonic.  A design that only
        violates the toggle margin can still be simulated (its margin is reported).
    """
    report = check_feasibility(design, mechanism)
    if not report.movable[0]:
        raise InfeasibleDesignError(report.message(0))
    return report


def constraint_margins(designs: np.ndarray, mechanism: FourBar) -> np.ndarray:
    """All constraint margins as one array for optimizers: (3,) -> (5,), (n, 3) -> (n, 5), >= 0 where satisfied.

    Columns are those of :class:`FeasibilityReport` (mm, mm, mm, deg, deg).  A design whose margins are undefined
    (never assembles) or whose lengths are not positive gets −1000 in every column, so that it counts as violated.
    """
    x = np.asarray(designs, dtype=float)
    flat = np.atleast_2d(x)
    valid = np.all(np.isfinite(flat) & (flat > 0), axis=1)
    out = np.full((flat.shape[0], len(MARGIN_NAMES)), -1e3)
    if valid.any():
        report = check_feasibility(flat[valid], mechanism)
        out[valid] = np.nan_to_num(np.column_stack([getattr(report, c) for c in MARGIN_NAMES]), nan=-1e3)
    return out[0] if x.ndim == 1 else out


def toggle_angle_deg(design: np.ndarray, mechanism: FourBar) -> float:
    """The toggle margin of one design as a quantity: the least over the stroke of min(ζ, 180° − ζ), ζ the
    crank–coupler angle at A (deg; 0 on the dead-centre line).  The constraint's margin ``toggle_deg`` is this
    minus the mechanism's ``toggle_margin_deg``; NaN when the design cannot move through the stroke."""
    report = check_feasibility(np.asarray(design, dtype=float)[None, :], mechanism)
    return float(report.toggle_deg[0] + mechanism.toggle_margin_deg)
