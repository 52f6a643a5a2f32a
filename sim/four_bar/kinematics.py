"""Position analysis of the four-bar O-A-B-C, driven by its output angle ψ (paper Eq. 2–5).

O is the origin, C = (x_C, y_C) the rocker's ground pivot, A = |OA|(cos θ, sin θ), B = C + |BC|(cos ψ, sin ψ).
The loop closure |B − A| = |AB| gives θ(ψ) in closed form (Eq. 4):

    θ = atan2(V, U) − arccos(W / √(U² + V²)) + π          (branch θ1, the arccos term subtracted)

The derivatives θ'(ψ) and θ''(ψ) follow by implicit differentiation of f(θ, ψ) = |B − A|² − |AB|² = 0, so they are
exact, not finite differences.  Lengths in any consistent unit (mm at the public surface), angles in rad.

The scalar kernels (``_``-prefixed, numba) are shared by the feasibility checks, the analytic dynamics and the
pymunk simulation, so every engine sees the same kinematics.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mechopt.errors import InputError

#: Branch of Eq. 4: −1 subtracts the arccos term (θ1, the paper's elbow-up), +1 adds it (θ2).
BRANCH_SUBTRACT = -1
BRANCH_ADD = 1


@njit(cache=True)
def _crank_kernel(oa, ab, bc, xc, yc, cpsi, spsi, branch):
    """Crank pin A and θ', θ'' at the output angle with cos ψ, sin ψ given; ``ok`` False where the loop is open.

    A is found as the intersection of the circles |A| = |OA| and |A − B| = |AB| without inverse trigonometry:
    with d = |OB| and û = B/d, A = a û + branch·h û⊥, a = (|OA|² − |AB|² + d²)/(2d), h = √(|OA|² − a²).  This is
    Eq. 4 exactly (cos(θ − ∠B) = a/|OA|), and it keeps the hot loops of the batch engines free of arccos/atan2.
    """
    xb = xc + bc * cpsi
    yb = yc + bc * spsi
    d2 = xb * xb + yb * yb
    d = np.sqrt(d2)
    if d == 0.0:
        return False, np.nan, np.nan, np.nan, np.nan
    a = (oa * oa - ab * ab + d2) / (2.0 * d)
    h2 = oa * oa - a * a
    if h2 < 0.0:
        return False, np.nan, np.nan, np.nan, np.nan
    h = np.sqrt(h2)
    ux = xb / d
    uy = yb / d
    ax = a * ux - branch * h * uy
    ay = a * uy + branch * h * ux
    ex = xb - ax  # e = B − A
    ey = yb - ay
    apx = -ay  # A'(θ)
    apy = ax
    bpx = -(yb - yc)  # B'(ψ)
    bpy = xb - xc
    f_t = -2.0 * (ex * apx + ey * apy)
    f_p = 2.0 * (ex * bpx + ey * bpy)
    if f_t == 0.0:
        # Crank and coupler aligned (toggle): θ' is unbounded.
        return True, ax, ay, np.inf, np.nan
    th1 = -f_p / f_t
    f_tt = 2.0 * oa * oa + 2.0 * (ex * ax + ey * ay)
    f_pp = 2.0 * bc * bc - 2.0 * (ex * (xb - xc) + ey * (yb - yc))
    f_tp = -2.0 * (apx * bpx + apy * bpy)
    th2 = -(f_tt * th1 * th1 + 2.0 * f_tp * th1 + f_pp) / f_t
    return True, ax, ay, th1, th2


@njit(cache=True)
def _theta_kernel(oa, ab, bc, xc, yc, psi, branch):
    """θ, θ', θ'' at output angle ψ (Eq. 4 and implicit differentiation); ``ok`` False where the loop is open."""
    ok, ax, ay, th1, th2 = _crank_kernel(oa, ab, bc, xc, yc, np.cos(psi), np.sin(psi), branch)
    if not ok:
        return False, np.nan, np.nan, np.nan
    return True, np.arctan2(ay, ax), th1, th2


@njit(cache=True)
def _psi_kernel(oa, ab, bc, xc, yc, theta, branch):
    """Forward kinematics: ψ and dψ/dθ at crank angle θ (same closed form, seen from C)."""
    ax = oa * np.cos(theta)
    ay = oa * np.sin(theta)
    dx = ax - xc
    dy = ay - yc
    u = -2.0 * bc * dx
    v = -2.0 * bc * dy
    w = dx * dx + dy * dy + bc * bc - ab * ab
    r = np.sqrt(u * u + v * v)
    if r == 0.0 or abs(w) > r:
        return False, np.nan, np.nan
    psi = np.arctan2(v, u) + branch * np.arccos(w / r) + np.pi
    xb = xc + bc * np.cos(psi)
    yb = yc + bc * np.sin(psi)
    ex = xb - ax
    ey = yb - ay
    num = ex * (-ay) + ey * ax  # e·A'
    den = ex * (-(yb - yc)) + ey * (xb - xc)  # e·B'
    if den == 0.0:
        return True, psi, np.inf
    return True, psi, num / den


@njit(cache=True)
def _transmission_kernel(oa, ab, bc, xc, yc, psi, theta):
    """Signed angle μ at B from B→C to B→A, and unsigned crank–coupler angle ζ at A between A→O and A→B (rad)."""
    ax = oa * np.cos(theta)
    ay = oa * np.sin(theta)
    xb = xc + bc * np.cos(psi)
    yb = yc + bc * np.sin(psi)
    cbx = xc - xb
    cby = yc - yb
    abx = ax - xb
    aby = ay - yb
    mu = np.arctan2(cbx * aby - cby * abx, cbx * abx + cby * aby)
    # ζ between A→O = −A and A→B = B − A.
    ox = -ax
    oy = -ay
    bx = xb - ax
    by = yb - ay
    zeta = np.arctan2(abs(ox * by - oy * bx), ox * bx + oy * by)
    return mu, zeta


@njit(cache=True)
def _theta_many(oa, ab, bc, xc, yc, psi, branch, out):
    for i in range(psi.size):
        ok, out[0, i], out[1, i], out[2, i] = _theta_kernel(oa, ab, bc, xc, yc, psi[i], branch)


@njit(cache=True)
def _psi_many(oa, ab, bc, xc, yc, theta, branch, out):
    for i in range(theta.size):
        ok, out[0, i], out[1, i] = _psi_kernel(oa, ab, bc, xc, yc, theta[i], branch)


def check_design(design: np.ndarray | tuple[float, float, float]) -> np.ndarray:
    """Validate one design (|OA|, |AB|, |BC|) in mm and return it as a float array.

    Raises
    ------
    InputError
        If the design does not have three finite, strictly positive lengths.
    """
    arr = np.asarray(design, dtype=float)
    if arr.shape != (3,):
        raise InputError(f"a design is three lengths (|OA|, |AB|, |BC|) in mm, got {design!r}")
    for name, value in zip(("|OA|", "|AB|", "|BC|"), arr, strict=True):
        if not np.isfinite(value) or value <= 0.0:
            raise InputError(f"{name} = {float(value):g} mm: expected a finite length > 0 mm")
    return arr


def crank_angle(
    design: np.ndarray | tuple[float, float, float],
    pivot_c: tuple[float, float],
    psi: np.ndarray | float,
    branch: int = BRANCH_SUBTRACT,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Crank angle θ(ψ) and its exact derivatives dθ/dψ, d²θ/dψ² (paper Eq. 4–5).

    Parameters
    ----------
    design : (3,) array_like
        |OA|, |AB|, |BC| in mm.
    pivot_c : (2,) array_like
        Rocker ground pivot C in mm, O being the origin.
    psi : array_like
        Output angles ψ (rad).
    branch : int
        ``-1`` for θ1 (arccos term subtracted, the ventilator's assembly) or ``+1`` for θ2.

    Returns
    -------
    theta, dtheta, ddtheta : ndarray
        θ in rad (in (−π, π], not unwrapped), dθ/dψ (–) and d²θ/dψ² (1/rad); NaN where the loop cannot close.
    """
    oa, ab, bc = check_design(design)
    psi = np.atleast_1d(np.asarray(psi, dtype=float))
    out = np.empty((3, psi.size))
    _theta_many(oa, ab, bc, float(pivot_c[0]), float(pivot_c[1]), psi.ravel(), int(branch), out)
    return out[0].reshape(psi.shape), out[1].reshape(psi.shape), out[2].reshape(psi.shape)


def rocker_angle(
    design: np.ndarray | tuple[float, float, float],
    pivot_c: tuple[float, float],
    theta: np.ndarray | float,
    branch: int = BRANCH_SUBTRACT,
) -> tuple[np.ndarray, np.ndarray]:
    """Forward kinematics: rocker angle ψ(θ) and dψ/dθ for crank angles θ.

    Parameters
    ----------
    design : (3,) array_like
        |OA|, |AB|, |BC| in mm.
    pivot_c : (2,) array_like
        Rocker ground pivot C in mm.
    theta : array_like
        Crank angles θ (rad).
    branch : int
        ``-1`` or ``+1``: which of the two circle intersections B is.

    Returns
    -------
    psi, dpsi : ndarray
        ψ in rad and dψ/dθ (–); NaN where the loop cannot close.
    """
    oa, ab, bc = check_design(design)
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    out = np.empty((2, theta.size))
    _psi_many(oa, ab, bc, float(pivot_c[0]), float(pivot_c[1]), theta.ravel(), int(branch), out)
    return out[0].reshape(theta.shape), out[1].reshape(theta.shape)


def joint_positions(
    design: np.ndarray | tuple[float, float, float],
    pivot_c: tuple[float, float],
    psi: np.ndarray | float,
    branch: int = BRANCH_SUBTRACT,
) -> dict[str, np.ndarray]:
    """Positions of the joints O, A, B, C (mm) at output angles ψ.

    Returns
    -------
    dict
        ``"O"``, ``"A"``, ``"B"``, ``"C"``: arrays of shape ``psi.shape + (2,)`` in mm.
    """
    oa, ab, bc = check_design(design)
    psi = np.asarray(psi, dtype=float)
    theta, _, _ = crank_angle(design, pivot_c, psi, branch)
    a = np.stack([oa * np.cos(theta), oa * np.sin(theta)], axis=-1)
    c = np.broadcast_to(np.asarray(pivot_c, dtype=float), a.shape)
    b = c + np.stack([bc * np.cos(psi), bc * np.sin(psi)], axis=-1)
    return {"O": np.zeros_like(a), "A": a, "B": b, "C": np.array(c)}


def validate_pivot(pivot_c: tuple[float, float]) -> tuple[float, float]:
    """Check that the rocker pivot C (mm) is two finite numbers and return it as floats."""
    xc, yc = (float(v) for v in pivot_c)
    if not (np.isfinite(xc) and np.isfinite(yc)):
        raise InputError(f"rocker pivot C = {pivot_c!r} mm: expected two finite coordinates")
    return xc, yc
