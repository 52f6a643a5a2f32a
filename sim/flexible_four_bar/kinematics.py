"""Closed-form rigid-body kinematics of the four-bar driven at a constant crank rate: assembly, branch, margins.

Frame O2 = (0, 0), O4 = (l1, 0); θ2 = ω t, B = l2 (cos θ2, sin θ2).  C is the intersection of the circles of
radius l3 about B and l4 about O4 on the side ``branch`` of the diagonal B → O4 (+1: on its left):

    d = |O4 − B|,  u = (O4 − B) / d,  p = (l3² − l4² + d²) / (2 d),  C = B + p u + branch sqrt(l3² − p²) u⊥,

θ3 the coupler's angle B → C and θ4 the follower's O4 → C.  Differentiating the loop B + l3 e3 = O4 + l4 e4 (e_i the
link's unit vector, n_i = e_i rotated by +90°) once and twice at α2 = 0 gives two 2 × 2 linear systems,

    l3 ω3 n3 − l4 ω4 n4 = −l2 ω n2,    l3 α3 n3 − l4 α4 n4 = l2 ω² e2 + l3 ω3² e3 − l4 ω4² e4,

singular only at the toggle positions (coupler and follower aligned, sin(θ3 − θ4) = 0).

The crank turns fully and the follower rocks (crank-rocker) exactly when the paper's three inequalities (Eq. 26)
hold, l2 + l4 < l1 + l3, l2 + l3 < l1 + l4, l1 + l2 < l3 + l4 (their pairwise sums give l2 < l1, l3, l4: the crank is
the shortest link and the linkage is Grashof); :func:`crank_rocker_margins` returns the three slacks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from mechopt.errors import InfeasibleDesignError

__all__ = ["RigidMotion", "crank_rocker_margins", "require_crank_rocker", "rigid_motion", "rigid_state",
           "transmission_angles"]


@njit(cache=True)
def rigid_state(l1: float, l2: float, l3: float, l4: float, omega: float, branch: float, t: float) -> tuple:
    """Rigid kinematics at one instant (SI): (θ2, θ3, θ4, ω3, ω4, α3, α4); NaN where the loop cannot close."""
    th2 = omega * t
    c2, s2 = math.cos(th2), math.sin(th2)
    bx, by = l2 * c2, l2 * s2
    dx, dy = l1 - bx, -by
    d = math.sqrt(dx * dx + dy * dy)
    p = (l3 * l3 - l4 * l4 + d * d) / (2.0 * d)
    hh = l3 * l3 - p * p
    if hh < 0.0 or d == 0.0:
        nan = math.nan
        return th2, nan, nan, nan, nan, nan, nan
    ux, uy = dx / d, dy / d
    q = branch * math.sqrt(hh)
    cx, cy = bx + p * ux - q * uy, by + p * uy + q * ux
    th3 = math.atan2(cy - by, cx - bx)
    th4 = math.atan2(cy, cx - l1)
    c3, s3, c4, s4 = math.cos(th3), math.sin(th3), math.cos(th4), math.sin(th4)
    # columns l3 n3 and −l4 n4; det = l3 l4 sin(θ3 − θ4)
    m11, m12, m21, m22 = -l3 * s3, l4 * s4, l3 * c3, -l4 * c4
    det = m11 * m22 - m12 * m21
    r1, r2 = l2 * omega * s2, -l2 * omega * c2
    w3 = (r1 * m22 - m12 * r2) / det
    w4 = (m11 * r2 - m21 * r1) / det
    r1 = l2 * omega**2 * c2 + l3 * w3 * w3 * c3 - l4 * w4 * w4 * c4
    r2 = l2 * omega**2 * s2 + l3 * w3 * w3 * s3 - l4 * w4 * w4 * s4
    a3 = (r1 * m22 - m12 * r2) / det
    a4 = (m11 * r2 - m21 * r1) / det
    return th2, th3, th4, w3, w4, a3, a4


@njit(cache=True)
def _rigid_table(l1, l2, l3, l4, omega, branch, t):
    out = np.empty((7, t.shape[0]))
    for i in range(t.shape[0]):
        state = rigid_state(l1, l2, l3, l4, omega, branch, t[i])
        for k in range(7):
            out[k, i] = state[k]
    return out


@dataclass(frozen=True)
class RigidMotion:
    """Rigid-body motion of the four-bar at times ``t`` (SI units; arrays of the shape of ``t``).

    Attributes
    ----------
    t, theta2 : ndarray
        Time (s) and crank angle (rad).
    theta3, omega3, alpha3 : ndarray
        Coupler angle B → C (rad), rate (rad/s) and angular acceleration (rad/s²).
    theta4, omega4, alpha4 : ndarray
        Follower angle O4 → C (rad), rate and angular acceleration.
    B, C : ndarray (n, 2)
        Joint positions (m).
    """

    t: np.ndarray
    theta2: np.ndarray
    theta3: np.ndarray
    theta4: np.ndarray
    omega3: np.ndarray
    omega4: np.ndarray
    alpha3: np.ndarray
    alpha4: np.ndarray
    B: np.ndarray
    C: np.ndarray


def rigid_motion(lengths: tuple[float, float, float, float], omega: float, t: np.ndarray,
                 branch: int = 1) -> RigidMotion:
    """Rigid kinematics of the four-bar over the times ``t``.

    Parameters
    ----------
    lengths : (float, float, float, float)
        l1, l2, l3, l4 (m).
    omega : float
        Constant crank rate (rad/s); θ2 = ω t.
    t : ndarray
        Times (s).
    branch : int
        Assembly branch (+1: C on the left of B → O4).

    Returns
    -------
    RigidMotion
        NaN angles where the loop cannot close.
    """
    l1, l2, l3, l4 = (float(v) for v in lengths)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    th2, th3, th4, w3, w4, a3, a4 = _rigid_table(l1, l2, l3, l4, float(omega), float(branch), t)
    B = l2 * np.stack([np.cos(th2), np.sin(th2)], axis=1)
    C = np.stack([l1 + l4 * np.cos(th4), l4 * np.sin(th4)], axis=1)
    return RigidMotion(t=t, theta2=th2, theta3=th3, theta4=th4, omega3=w3, omega4=w4, alpha3=a3, alpha4=a4,
                       B=B, C=C)


def crank_rocker_margins(X: np.ndarray) -> np.ndarray:
    """The paper's crank-rocker inequalities (Eq. 26) as slacks, vectorised (lengths in any one unit).

    Parameters
    ----------
    X : ndarray (n, 4)
        l1, l2, l3, l4 of each design.

    Returns
    -------
    ndarray (n, 3)
        l1 + l3 − l2 − l4, l1 + l4 − l2 − l3, l3 + l4 − l1 − l2: all > 0 for a crank-rocker, 0 at a toggle.
    """
    X = np.atleast_2d(np.asarray(X, dtype=float))
    l1, l2, l3, l4 = X[:, 0], X[:, 1], X[:, 2], X[:, 3]
    return np.stack([l1 + l3 - l2 - l4, l1 + l4 - l2 - l3, l3 + l4 - l1 - l2], axis=1)


def transmission_angles(lengths: tuple[float, float, float, float]) -> tuple[float, float]:
    """Smallest and largest transmission angle μ = angle between coupler and follower over a crank turn (rad).

    By the law of cosines in the triangle B C O4, cos μ = (l3² + l4² − d²) / (2 l3 l4) with d = |O4 − B| between
    l1 − l2 (θ2 = 0) and l1 + l2 (θ2 = π).
    """
    l1, l2, l3, l4 = (float(v) for v in lengths)

    def mu(d: float) -> float:
        return math.acos(min(1.0, max(-1.0, (l3 * l3 + l4 * l4 - d * d) / (2.0 * l3 * l4))))

    return mu(abs(l1 - l2)), mu(l1 + l2)


def require_crank_rocker(lengths: tuple[float, float, float, float]) -> None:
    """Raise :class:`InfeasibleDesignError` unless the crank turns fully and the follower rocks (Eq. 26)."""
    m = crank_rocker_margins(np.array([lengths]))[0]
    if not np.all(m > 0.0):
        names = ("l1 + l3 > l2 + l4", "l1 + l4 > l2 + l3", "l3 + l4 > l1 + l2")
        bad = [n for n, v in zip(names, m, strict=True) if not v > 0.0]
        raise InfeasibleDesignError(f"flexible four-bar {tuple(round(v * 1e3, 4) for v in lengths)} mm is not a "
                                    f"crank-rocker: {', '.join(bad)} fails")
