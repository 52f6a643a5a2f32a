"""What drives each flexible link's bending: its rigid-body transverse acceleration field and its axial force.

Each link is described in its chord frame (origin at its first joint, e along the link, n = e rotated by +90°):
the coupler from B (s = 0) to C (s = l3), the follower from O4 (s = 0) to C (s = l4).  Its rigid-body acceleration
is linear in s, a(s) = a_0 + α n s − ω² e s, so the transverse inertia load per length is −ρA (a⊥0 + α s) (the
right-hand side −M Ü_r of the paper's Eq. 9).

The axial force N(s) = c0 + c1 s + c2 s² (tension > 0) follows from the rigid-body dynamics of the two uniform links
(no gravity, no external load).  With F_C the force of the follower on the coupler at C, the moments about B (coupler,
Σ M_B = I_G α3 + (l3/2) e3 × m3 a_G3) and about the fixed O4 (follower, Σ M_O4 = m4 l4² α4 / 3) give

    F_C · n3 = m3 (a_B⊥ / 2 + l3 α3 / 3),    F_C · n4 = −m4 l4 α4 / 3,

and F_B = m3 a_G3 − F_C, F_O4 = m4 a_G4 + F_C.  Integrating ρA a∥ from the first joint:

    coupler   N3(s) = −F_B · e3 + ρA3 (a_B∥ s − ω3² s² / 2),     follower   N4(s) = −F_O4 · e4 − ρA4 ω4² s² / 2.

The modal engine uses N only for its optional geometric stiffness (the paper's model has none).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from mechopt.errors import InputError
from mechopt.sim.flexible_four_bar.kinematics import rigid_state

__all__ = ["DRIVE_COLUMNS", "drive_table", "drive_tables", "euler_load_ratios", "link_drives"]

#: Columns of a drive row: axial force coefficients c0 (N), c1 (N/m), c2 (N/m²), transverse acceleration of the
#: link's first joint a⊥0 (m/s²), the link's angular acceleration α (rad/s²), its angular rate ω (rad/s), and the
#: shift of c0 per unit moment of elastic inertia ∫ ρA s ẅ ds of this link and of the other one (1/m); the same
#: coefficients turn the chords' shortening δ̈ into the links' extra angular accelerations (:mod:`.modal`).
DRIVE_COLUMNS = ("c0", "c1", "c2", "a_perp0", "alpha", "omega", "k_self", "k_other")


@njit(cache=True)
def link_drives(l1, l2, l3, l4, omega, branch, m3, m4, t, out3, out4):
    """Drive rows of the coupler (``out3``) and follower (``out4``) at time t (see :data:`DRIVE_COLUMNS`).

    ``m3``, ``m4`` are the links' masses ρA l (kg).  Returns False where the loop cannot close.
    """
    th2, th3, th4, w3, w4, a3, a4 = rigid_state(l1, l2, l3, l4, omega, branch, t)
    if math.isnan(th3):
        return False
    c2, s2 = math.cos(th2), math.sin(th2)
    e3x, e3y, e4x, e4y = math.cos(th3), math.sin(th3), math.cos(th4), math.sin(th4)
    n3x, n3y, n4x, n4y = -e3y, e3x, -e4y, e4x
    abx, aby = -l2 * omega**2 * c2, -l2 * omega**2 * s2  # crank tip B at constant ω
    ab_par, ab_perp = abx * e3x + aby * e3y, abx * n3x + aby * n3y
    # centres of mass
    ag3x = abx + 0.5 * l3 * (a3 * n3x - w3 * w3 * e3x)
    ag3y = aby + 0.5 * l3 * (a3 * n3y - w3 * w3 * e3y)
    ag4x = 0.5 * l4 * (a4 * n4x - w4 * w4 * e4x)
    ag4y = 0.5 * l4 * (a4 * n4y - w4 * w4 * e4y)
    r3 = m3 * (0.5 * ab_perp + l3 * a3 / 3.0)
    r4 = -m4 * l4 * a4 / 3.0
    det = n3x * n4y - n3y * n4x
    fcx = (r3 * n4y - n3y * r4) / det
    fcy = (n3x * r4 - n4x * r3) / det
    fbx, fby = m3 * ag3x - fcx, m3 * ag3y - fcy
    fox, foy = m4 * ag4x + fcx, m4 * ag4y + fcy
    rho_a3, rho_a4 = m3 / l3, m4 / l4
    out3[0] = -(fbx * e3x + fby * e3y)
    out3[1] = rho_a3 * ab_par
    out3[2] = -0.5 * rho_a3 * w3 * w3
    out3[3] = ab_perp
    out3[4] = a3
    out3[5] = w3
    # the links' elastic inertia adds S3 / l3 to F_C · n3 and −S4 / l4 to F_C · n4 (S = ∫ ρA s ẅ ds): c0 shifts
    cos34 = e3x * e4x + e3y * e4y
    out3[6] = cos34 / (l3 * det)
    out3[7] = 1.0 / (l4 * det)
    out4[0] = -(fox * e4x + foy * e4y)
    out4[1] = 0.0
    out4[2] = -0.5 * rho_a4 * w4 * w4
    out4[3] = 0.0
    out4[4] = a4
    out4[5] = w4
    out4[6] = -cos34 / (l4 * det)
    out4[7] = -1.0 / (l3 * det)
    return True


@njit(cache=True)
def _tables(l1, l2, l3, l4, omega, branch, m3, m4, t):
    out3 = np.empty((t.shape[0], 8))
    out4 = np.empty((t.shape[0], 8))
    for i in range(t.shape[0]):
        if not link_drives(l1, l2, l3, l4, omega, branch, m3, m4, t[i], out3[i], out4[i]):
            out3[i, :] = np.nan
            out4[i, :] = np.nan
    return out3, out4


def drive_tables(lengths: tuple[float, float, float, float], omega: float, branch: int,
                 masses: tuple[float, float], t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Drive rows of the coupler and of the follower at the times ``t``.

    Parameters
    ----------
    lengths : (float, float, float, float)
        l1, l2, l3, l4 (m).
    omega : float
        Crank rate (rad/s).
    branch : int
        Assembly branch.
    masses : (float, float)
        Coupler and follower masses (kg).
    t : ndarray
        Times (s).

    Returns
    -------
    (ndarray, ndarray), each (len(t), 8)
        Columns :data:`DRIVE_COLUMNS`; NaN rows where the loop cannot close.
    """
    l1, l2, l3, l4 = (float(v) for v in lengths)
    t = np.ascontiguousarray(np.atleast_1d(np.asarray(t, dtype=float)))
    return _tables(l1, l2, l3, l4, float(omega), float(branch), float(masses[0]), float(masses[1]), t)


def drive_table(lengths: tuple[float, float, float, float], omega: float, branch: int,
                masses: tuple[float, float], t: np.ndarray, link: int) -> np.ndarray:
    """Drive rows of link 3 (coupler) or 4 (follower) at the times ``t`` (see :func:`drive_tables`)."""
    if link not in (3, 4):
        raise InputError(f"link = {link!r}; expected 3 (coupler) or 4 (follower)")
    return drive_tables(lengths, omega, branch, masses, t)[link - 3]


def euler_load_ratios(p, n_points: int = 361) -> tuple[float, float]:
    """Largest compressive axial force of the coupler and of the follower over a crank turn, over its Euler load.

    N(s, t) from the rigid-body dynamics (no elastic inertia), sampled at ``n_points`` crank angles and 21 points
    along each link; P_E = π² EI / l².  Where it exceeds ~0.1 the deflection is several % of the length and the
    linear model (even with its geometric stiffness) and the geometrically exact engine part (README).

    Parameters
    ----------
    p : FlexibleFourBar
        The design (SI).
    n_points : int
        Crank angles over one turn.

    Returns
    -------
    (float, float)
        max(−N) / P_E of the coupler and of the follower (0 if a link is never compressed).
    """
    t = np.linspace(0.0, 2.0 * np.pi / p.omega, n_points)
    masses = (p.coupler.mass_per_length * p.l3, p.follower.mass_per_length * p.l4)
    out = []
    for d, link, length in zip(drive_tables(p.lengths, p.omega, p.branch, masses, t), (p.coupler, p.follower),
                               (p.l3, p.l4), strict=True):
        s = np.linspace(0.0, length, 21)
        n = d[:, :1] + d[:, 1:2] * s + d[:, 2:3] * s * s
        out.append(max(0.0, float(-np.min(n))) / (np.pi**2 * link.bending_stiffness / length**2))
    return out[0], out[1]
