"""Position analysis of the slider-crank O-A-B in closed form, with exact derivatives in the crank angle.

O is the origin, A = r (cos θ, sin θ) the crank pin, and the slider pin B = (x, h) runs on the line y = h, parallel
to x at the offset h from O.  The loop closure |B − A| = l gives

    u = h − r sin θ,   w = √(l² − u²),   x(θ) = r cos θ + s w          (s = +1: B on the +x side of A)

and implicit differentiation gives, exactly,

    x'  = −r sin θ + s r cos θ · u / w
    x'' = −r cos θ − s r sin θ · u / w − s r² l² cos² θ / w³.

The rod angle φ (A→B from +x) has sin φ = u / l, φ' = −r cos θ / (s w).  The transmission angle is the one of paper
001 (its Fig. 2): TA = 90° + asin(u / l), the angle between the rod and the normal to the slider line, 90° when the
rod is parallel to that line; |TA − 90°| is the rod's inclination to the line.  Lengths in any consistent unit
(mm at the public surface), angles in rad.

The scalar kernel (numba) is shared by the feasibility checks, the analytic dynamics and the pymunk engine.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mechopt.errors import InputError

#: Assembly branch: +1 puts the slider on the +x side of the crank pin (papers 001 and 003), −1 on the −x side.
BRANCH_RIGHT = 1
BRANCH_LEFT = -1


@njit(cache=True)
def _slider_kernel(r, l, h, c, s, branch):
    """x, x', x'', φ, φ', φ'' at the crank angle with cos θ = c, sin θ = s; ``ok`` False where the loop is open.

    At w = 0 (rod perpendicular to the slider line) the position exists but the derivatives are unbounded.
    """
    u = h - r * s
    w2 = l * l - u * u
    if w2 < 0.0:
        return False, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan
    w = np.sqrt(w2)
    x = r * c + branch * w
    phi = np.arctan2(u, branch * w)
    if w == 0.0:
        return True, x, np.inf, np.nan, phi, np.inf, np.nan
    x1 = -r * s + branch * r * c * u / w
    x2 = -r * c - branch * r * s * u / w - branch * r * r * l * l * c * c / (w2 * w)
    phi1 = -r * c / (branch * w)
    # d/dθ of −r cos θ / (s w), with w' = r cos θ · u / w.
    phi2 = (r * s * w + r * c * (r * c * u / w)) / (branch * w2)
    return True, x, x1, x2, phi, phi1, phi2


@njit(cache=True)
def _slider_many(r, l, h, theta, branch, out):
    for i in range(theta.size):
        ok, out[0, i], out[1, i], out[2, i], out[3, i], out[4, i], out[5, i] = _slider_kernel(
            r, l, h, np.cos(theta[i]), np.sin(theta[i]), branch)


def check_design(design: np.ndarray | tuple[float, float, float]) -> np.ndarray:
    """Validate one design (r, l, h) in mm: crank |OA|, rod |AB|, slider-line offset h; return it as floats.

    Raises
    ------
    InputError
        Unless r and l are finite and > 0 and h is finite.
    """
    arr = np.asarray(design, dtype=float)
    if arr.shape != (3,):
        raise InputError(f"a slider-crank design is (r, l, h) in mm, got {design!r}")
    for name, value in zip(("crank r", "rod l"), arr[:2], strict=True):
        if not np.isfinite(value) or value <= 0.0:
            raise InputError(f"{name} = {float(value):g} mm: expected a finite length > 0 mm")
    if not np.isfinite(arr[2]):
        raise InputError(f"offset h = {float(arr[2]):g} mm: expected a finite number")
    return arr


def check_branch(branch: int) -> int:
    """Return ``branch`` if it is +1 or −1, else raise a one-line :class:`InputError`."""
    if branch not in (BRANCH_RIGHT, BRANCH_LEFT):
        raise InputError(f"branch = {branch!r}: expected +1 (slider on the +x side of A) or -1")
    return int(branch)


def slider_position(
    design: np.ndarray | tuple[float, float, float], theta: np.ndarray | float, branch: int = BRANCH_RIGHT
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Slider position x(θ) and its exact derivatives dx/dθ, d²x/dθ².

    Parameters
    ----------
    design : (3,) array_like
        Crank r, rod l and offset h, in mm.
    theta : array_like
        Crank angles θ (rad).
    branch : int
        +1: slider on the +x side of the crank pin; −1: on the −x side.

    Returns
    -------
    x, dx, ddx : ndarray
        x in mm from O along the slider line's direction, dx/dθ (mm/rad), d²x/dθ² (mm/rad²); NaN where the rod
        cannot reach the line.
    """
    out = _kinematics(design, theta, branch)
    return out[0], out[1], out[2]


def rod_angle(
    design: np.ndarray | tuple[float, float, float], theta: np.ndarray | float, branch: int = BRANCH_RIGHT
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rod angle φ(θ) of A→B from +x and its exact derivatives dφ/dθ (–), d²φ/dθ² (1/rad); NaN where open."""
    out = _kinematics(design, theta, branch)
    return out[3], out[4], out[5]


def _kinematics(design, theta, branch) -> np.ndarray:
    r, l, h = check_design(design)
    theta = np.asarray(theta, dtype=float)
    flat = np.ascontiguousarray(np.atleast_1d(theta).ravel())
    out = np.empty((6, flat.size))
    _slider_many(r, l, h, flat, check_branch(branch), out)
    return out.reshape((6,) + theta.shape)


def transmission_angle(design: np.ndarray | tuple[float, float, float], theta: np.ndarray | float) -> np.ndarray:
    """Transmission angle TA(θ) = 90° + asin((h − r sin θ)/l) of paper 001, in degrees; NaN where open."""
    r, l, h = check_design(design)
    ratio = (h - r * np.sin(np.asarray(theta, dtype=float))) / l
    with np.errstate(invalid="ignore"):
        return 90.0 + np.degrees(np.where(np.abs(ratio) <= 1.0, np.arcsin(np.clip(ratio, -1, 1)), np.nan))


def transmission_extremes(r: np.ndarray | float, l: np.ndarray | float, h: np.ndarray | float
                          ) -> tuple[np.ndarray, np.ndarray]:
    """Exact extremes of the transmission angle over a full crank revolution (vectorised), in degrees.

    sin θ sweeps [−1, 1], so (h − r sin θ)/l sweeps [(h − r)/l, (h + r)/l]: TA_min = 90° + asin((h − r)/l) at
    θ = 90° and TA_max = 90° + asin((h + r)/l) at θ = 270°.  NaN where the crank cannot turn fully (r + |h| > l).

    Parameters
    ----------
    r, l, h : array_like
        Crank, rod (> 0) and offset, in one length unit.
    """
    r, l, h = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (r, l, h)))
    lo = (h - r) / l
    hi = (h + r) / l
    ok = (np.abs(lo) <= 1.0) & (np.abs(hi) <= 1.0)
    with np.errstate(invalid="ignore"):
        ta_min = np.where(ok, 90.0 + np.degrees(np.arcsin(np.clip(lo, -1, 1))), np.nan)
        ta_max = np.where(ok, 90.0 + np.degrees(np.arcsin(np.clip(hi, -1, 1))), np.nan)
    return ta_min, ta_max


def joint_positions(
    design: np.ndarray | tuple[float, float, float], theta: np.ndarray | float, branch: int = BRANCH_RIGHT
) -> dict[str, np.ndarray]:
    """Positions of O, A, B (mm) at crank angles θ: arrays of shape ``theta.shape + (2,)``; B NaN where open."""
    r, _, h = check_design(design)
    theta = np.asarray(theta, dtype=float)
    x, _, _ = slider_position(design, theta, branch)
    a = np.stack([r * np.cos(theta), r * np.sin(theta)], axis=-1)
    b = np.stack([x, np.full_like(x, h)], axis=-1)
    return {"O": np.zeros_like(a), "A": a, "B": b}
