"""Feasibility of slider-crank designs over a full crank revolution, as named margins (>= 0 satisfied).

* **assembly** (mm): the rod reaches the slider line at every crank angle, l − max_θ |h − r sin θ| = l − r − |h|;
  for a crank that turns fully this is also the full-rotation (Grashof-type) condition r + |h| <= l.
* **transmission angle** (deg): TA = 90° + asin((h − r sin θ)/l) stays in [TA_lo, TA_hi] over the revolution;
  its extremes are exact (θ = 90° and 270°, see :func:`kinematics.transmission_extremes`), so the margins are
  TA_min − TA_lo and TA_hi − TA_max.

Vectorised over designs (numpy, closed form: no sampling of θ).
"""

from __future__ import annotations

import numpy as np

from mechopt.errors import InfeasibleDesignError, InputError
from mechopt.sim.slider_crank.kinematics import transmission_extremes

COLUMNS = ("assembly_mm", "ta_low_deg", "ta_high_deg")


def as_designs(designs: np.ndarray) -> np.ndarray:
    """Validate designs (n, 3) = (r, l, h) in mm and return them as floats (r, l finite > 0, h finite)."""
    arr = np.atleast_2d(np.asarray(designs, dtype=float))
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"slider-crank designs must be an (n, 3) array of r, l, h in mm, got shape {arr.shape}")
    bad = ~np.isfinite(arr) | np.column_stack([arr[:, :2] <= 0, np.zeros(len(arr), bool)])
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise InputError(f"{('r', 'l', 'h')[j]} = {arr[i, j]:g} mm in design {i}: expected a finite length"
                         f"{' > 0' if j < 2 else ''} (mm)")
    return arr


def margins(designs: np.ndarray, ta_limits_deg: tuple[float, float] = (45.0, 135.0)) -> np.ndarray:
    """Margins of designs over a full revolution: columns :data:`COLUMNS` (mm, deg, deg).

    Parameters
    ----------
    designs : (n, 3) or (3,) array_like
        r, l, h in mm.
    ta_limits_deg : (float, float)
        Allowed transmission-angle range (deg).

    Returns
    -------
    (n, 3) ndarray
        assembly (mm), TA_min − TA_lo and TA_hi − TA_max (deg); where the crank cannot turn fully the angle
        margins are −90° (undefined angles count as violated).
    """
    arr = as_designs(designs)
    r, l, h = arr.T
    ta_min, ta_max = transmission_extremes(r, l, h)
    out = np.column_stack([l - r - np.abs(h), ta_min - ta_limits_deg[0], ta_limits_deg[1] - ta_max])
    out[:, 1:] = np.nan_to_num(out[:, 1:], nan=-90.0)
    return out


def require_assemblable(design: np.ndarray, ta_limits_deg: tuple[float, float] = (45.0, 135.0)) -> np.ndarray:
    """Margins (3,) of one design; raise :class:`InfeasibleDesignError` unless its crank turns fully.

    A zero assembly margin (r + |h| = l) is refused too: there the rod stands perpendicular to the slider line
    and dx/dθ is unbounded.
    """
    m = margins(design, ta_limits_deg)[0]
    if not m[0] > 0:
        r, l, h = np.ravel(design)
        raise InfeasibleDesignError(f"design r={r:.3f} l={l:.3f} h={h:.3f} mm: the crank cannot turn fully "
                                    f"(r + |h| - l = {-m[0]:.3f} mm, must be < 0)")
    return m
