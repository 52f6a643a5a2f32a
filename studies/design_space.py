"""The design space of a study as the surrogate sees it: coordinates, box and predicates.

The surrogate works in the paper's coordinates U = (u, v, w) = (|OA|, |BC|, |AB|); designs everywhere else are
(|OA|, |AB|, |BC|).  The permutation is its own inverse and lives here, in one place, so the paper's Δ and origin can
be read in as printed.  Two predicates matter:

* **feasible**: in the box of interest and satisfying every constraint — where the optimum must lie;
* **sampleable**: where the objective may be simulated to build the model — a slightly larger box and a relaxed
  toggle margin (the design rule, not physics), still movable.  Lines that run on there span the feasible region's
  whole extent, so the line models need not extrapolate inside the hull.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from mechopt.sim.fourbar.feasibility import check_feasibility
from mechopt.sim.fourbar.mechanism import FourBar

#: Index permutation design (oa, ab, bc) <-> paper coordinates U (oa, bc, ab); its own inverse.
PAPER_ORDER = (0, 2, 1)


def to_u(designs: np.ndarray) -> np.ndarray:
    """Designs (…, 3) as (|OA|, |AB|, |BC|) → paper coordinates (|OA|, |BC|, |AB|), mm."""
    return np.asarray(designs, dtype=float)[..., list(PAPER_ORDER)]


def from_u(u: np.ndarray) -> np.ndarray:
    """Paper coordinates (…, 3) as (|OA|, |BC|, |AB|) → designs (|OA|, |AB|, |BC|), mm."""
    return np.asarray(u, dtype=float)[..., list(PAPER_ORDER)]


@dataclass(frozen=True)
class DesignSpace:
    """Box, mechanism and the two predicates, in design or paper coordinates.

    Parameters
    ----------
    mechanism : FourBar
        The mechanism (constraints).
    box : (3, 2) ndarray
        Bounds of (|OA|, |AB|, |BC|) in mm.
    toggle_relax_deg : float
        How far below the toggle margin lines may be sampled (deg).
    box_extend : float
        Fraction of the box width by which lines may run beyond the box.
    n_check : int
        ψ samples per design in the fast predicate used on search grids (the final design is checked with the
        default, finer one).
    """

    mechanism: FourBar
    box: np.ndarray
    toggle_relax_deg: float = 5.0
    box_extend: float = 0.15
    n_check: int = 61

    def in_box(self, designs: np.ndarray, extend: float = 0.0) -> np.ndarray:
        """Designs (n, 3) inside the box, widened by ``extend`` times its width."""
        d = np.atleast_2d(designs)
        w = self.box[:, 1] - self.box[:, 0]
        return np.all((d >= self.box[:, 0] - extend * w) & (d <= self.box[:, 1] + extend * w), axis=1)

    def feasible(self, designs: np.ndarray, n_check: int | None = None) -> np.ndarray:
        """Designs (n, 3) in mm inside the box and satisfying every constraint."""
        d = np.atleast_2d(np.asarray(designs, dtype=float))
        ok = self.in_box(d)
        out = np.zeros(d.shape[0], dtype=bool)
        if ok.any():
            kwargs = {} if n_check is None else {"n_check": n_check}
            out[ok] = check_feasibility(d[ok], self.mechanism, **kwargs).feasible
        return out

    def sampleable(self, designs: np.ndarray) -> np.ndarray:
        """Designs (n, 3) in mm that may be simulated to build the model (see the module docstring)."""
        d = np.atleast_2d(np.asarray(designs, dtype=float))
        ok = self.in_box(d, self.box_extend) & np.all(d > 0, axis=1)
        out = np.zeros(d.shape[0], dtype=bool)
        if ok.any():
            report = check_feasibility(d[ok], self.mechanism)
            with np.errstate(invalid="ignore"):
                out[ok] = report.movable & (report.toggle_deg >= -self.toggle_relax_deg)
        return out

    def feasible_u(self, u: np.ndarray) -> np.ndarray:
        """:meth:`feasible` in paper coordinates."""
        return self.feasible(from_u(u))

    def feasible_u_fast(self, u: np.ndarray) -> np.ndarray:
        """:meth:`feasible` in paper coordinates with the coarser along-stroke check, for search grids."""
        return self.feasible(from_u(u), n_check=self.n_check)

    def sampleable_u(self, u: np.ndarray) -> np.ndarray:
        """:meth:`sampleable` in paper coordinates."""
        return self.sampleable(from_u(u))

    def sub_space(self, center: np.ndarray, fraction: float) -> DesignSpace:
        """The same space restricted to a box of ``fraction`` times the width around ``center`` (mm)."""
        w = self.box[:, 1] - self.box[:, 0]
        lo = np.maximum(self.box[:, 0], center - 0.5 * fraction * w)
        hi = np.minimum(self.box[:, 1], center + 0.5 * fraction * w)
        # Keep the sub-box's full width when the centre is near a face: shift it inwards instead of cropping.
        lo = np.where(hi - lo < fraction * w, np.maximum(self.box[:, 0], hi - fraction * w), lo)
        hi = np.where(hi - lo < fraction * w, np.minimum(self.box[:, 1], lo + fraction * w), hi)
        return DesignSpace(self.mechanism, np.column_stack([lo, hi]), self.toggle_relax_deg, self.box_extend,
                           self.n_check)
