"""The coupler point of paper 000's slider-crank as a function of the crank angle φ, on either assembly branch K.

Local frame O'X'Y' (paper Fig. 1): the crank O'A of length a1 turns about O' by φ; the rod AB of length a2 makes the
angle θ with X'; the slider B runs on the line y' = a5.  The loop closure (Eqs. 1-4) gives

    sin θ = u = (a5 − a1 sin φ) / a2,    cos θ = c = K √(1 − u²),    K = ±1,

and the coupler point P lies a3 from A along the rod and a4 to its left (Eqs. 5-6, with cos(θ − 3π/2) = −sin θ):

    x' = a1 cos φ + a3 c − a4 u,    y' = (a3 − a2) u + a5 + a4 c.

The printed Eq. 8 multiplies the first term of y' by a stray cos φ; Eq. 6 has none, and neither has this module.
The global point (Eqs. 9-10) is x = x' cos a6 − y' sin a6 + a8, y = x' sin a6 + y' cos a6 + a7: a6 rotates the local
frame, a7 translates it along y and a8 along x.  (a5, a6, K, φ) and (−a5, a6 + π, −K, φ + π) are one linkage: the
local point changes sign and the extra half-turn of a6 turns it back.

Lengths are in the unit of the desired points (the paper gives none), angles in rad.  A design is the array
(a1, ..., a8); the crank turns fully when a2 − a1 − |a5| >= 0 (:mod:`.feasibility`).  Where it does not, 1 − u² < 0 is
clipped to 0 (the rod stands perpendicular to the slider line): a continuation, not a position of the mechanism.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["BRANCHES", "coupler_point", "coupler_point_derivatives", "linkage_joints"]

#: The two assembly branches K of Eq. 4.
BRANCHES = (1, -1)


def _local(design: np.ndarray, phi: np.ndarray, branch: int) -> tuple[np.ndarray, ...]:
    a1, a2, a3, a4, a5 = (float(v) for v in design[:5])
    u = (a5 - a1 * np.sin(phi)) / a2
    c = branch * np.sqrt(np.clip(1.0 - u * u, 0.0, None))
    return u, c, a1 * np.cos(phi) + a3 * c - a4 * u, (a3 - a2) * u + a5 + a4 * c


def coupler_point(design: np.ndarray, phi: np.ndarray | float, branch: int) -> tuple[np.ndarray, np.ndarray]:
    """Global coordinates of the coupler point P at crank angles φ (Eqs. 5-6 and 9-10).

    Parameters
    ----------
    design : (8,) array_like
        (a1, ..., a8): crank, rod, position of P along and across the rod, slider-line offset (lengths), frame
        rotation a6 (rad), frame translation a7 along y and a8 along x (lengths).
    phi : float or ndarray
        Crank angles (rad).
    branch : int
        Assembly branch K = +1 or −1 (the sign of cos θ).

    Returns
    -------
    x, y : ndarray
        Coordinates of P, shaped like ``phi`` (lengths).
    """
    a = np.asarray(design, dtype=float)
    _, _, xl, yl = _local(a, np.asarray(phi, dtype=float), branch)
    ca, sa = math.cos(a[5]), math.sin(a[5])
    return xl * ca - yl * sa + a[7], xl * sa + yl * ca + a[6]


def linkage_joints(design: np.ndarray, phi: np.ndarray | float, branch: int) -> dict[str, np.ndarray]:
    """Global positions of the crank pivot O', crank pin A, slider B and coupler point P, each (..., 2).

    Parameters
    ----------
    design : (8,) array_like
        (a1, ..., a8), see :func:`coupler_point`.
    phi : float or ndarray
        Crank angles (rad).
    branch : int
        K = ±1.

    Returns
    -------
    dict
        ``{"O": ..., "A": ..., "B": ..., "P": ...}`` and ``"slider_line"``: two points of the line y' = a5.
    """
    a = np.asarray(design, dtype=float)
    phi = np.asarray(phi, dtype=float)
    u, c, xl, yl = _local(a, phi, branch)
    ca, sa = math.cos(a[5]), math.sin(a[5])

    def to_global(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        return np.stack([x * ca - y * sa + a[7], x * sa + y * ca + a[6]], axis=-1)

    ax_, ay_ = a[0] * np.cos(phi), a[0] * np.sin(phi)
    reach = a[0] + a[1] + abs(a[2]) + abs(a[3])
    return {"O": to_global(np.zeros_like(phi), np.zeros_like(phi)), "A": to_global(ax_, ay_),
            "B": to_global(ax_ + a[1] * c, ay_ + a[1] * u), "P": to_global(xl, yl),
            "slider_line": to_global(np.array([-reach, reach]), np.array([a[4], a[4]]))}


@njit(cache=True)
def coupler_point_derivatives(design: np.ndarray, branch: int, phi: float) -> tuple[float, float, float, float,
                                                                                     float, float]:
    """P(φ), dP/dφ and d²P/dφ² in global coordinates (numba; the kernel of the closest-point search).

    Parameters
    ----------
    design : (8,) float64 ndarray
        (a1, ..., a8).
    branch : int
        K = ±1.
    phi : float
        Crank angle (rad).

    Returns
    -------
    tuple of float
        (x, y, x', y', x'', y'') with primes d/dφ.  At a dead point of the rod (c = 0) the derivatives are infinite
        or NaN; callers fall back to bisection there.
    """
    a1, a2, a3, a4, a5 = design[0], design[1], design[2], design[3], design[4]
    s, co = math.sin(phi), math.cos(phi)
    u = (a5 - a1 * s) / a2
    du = -a1 * co / a2
    ddu = a1 * s / a2
    c = branch * math.sqrt(max(1.0 - u * u, 0.0))
    dc = -u * du / c if c != 0.0 else math.inf
    ddc = -(du * du + u * ddu) / c - (u * du) ** 2 / c**3 if c != 0.0 else math.inf
    xl = a1 * co + a3 * c - a4 * u
    yl = (a3 - a2) * u + a5 + a4 * c
    dxl = -a1 * s + a3 * dc - a4 * du
    dyl = (a3 - a2) * du + a4 * dc
    ddxl = -a1 * co + a3 * ddc - a4 * ddu
    ddyl = (a3 - a2) * ddu + a4 * ddc
    ca, sa = math.cos(design[5]), math.sin(design[5])
    return (xl * ca - yl * sa + design[7], xl * sa + yl * ca + design[6], dxl * ca - dyl * sa, dxl * sa + dyl * ca,
            ddxl * ca - ddyl * sa, ddxl * sa + ddyl * ca)
