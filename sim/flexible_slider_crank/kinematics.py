"""Closed-form rigid-body kinematics of the in-line slider-crank driven at a constant crank rate.

Crank angle θ = ω t, A = r (cos θ, sin θ), slider B = (x, 0) with

    x = r cos θ + sqrt(l² − r² sin² θ),

rod direction e = (B − A) / l at the angle φ = −asin(λ sin θ), λ = r / l.  Differentiating twice in time gives the
slider velocity and acceleration and the rod's angular rate and acceleration used to drive the elastic rod.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = ["RigidMotion", "rigid_motion", "rigid_state"]


@dataclass(frozen=True)
class RigidMotion:
    """Rigid-body motion of the slider-crank at times ``t`` (SI units; arrays of the shape of ``t``).

    Attributes
    ----------
    t, theta : ndarray
        Time (s) and crank angle (rad).
    x, v, acc : ndarray
        Slider position (m), velocity (m/s) and acceleration (m/s²) along x.
    phi, phi_d, phi_dd : ndarray
        Rod angle from +x (rad), its rate (rad/s) and acceleration (rad/s²).
    aA_par, aA_perp : ndarray
        Acceleration of A along the rod (A→B) and across it (the rod's +90° normal) (m/s²).
    """

    t: np.ndarray
    theta: np.ndarray
    x: np.ndarray
    v: np.ndarray
    acc: np.ndarray
    phi: np.ndarray
    phi_d: np.ndarray
    phi_dd: np.ndarray
    aA_par: np.ndarray
    aA_perp: np.ndarray


@njit(cache=True)
def rigid_state(r: float, l: float, omega: float, t: float) -> tuple:
    """Rigid kinematics at one instant (SI): (θ, x, v, acc, φ, φ̇, φ̈, a_A∥, a_A⊥), see :class:`RigidMotion`."""
    th = omega * t
    s, c = math.sin(th), math.cos(th)
    root = math.sqrt(l * l - r * r * s * s)
    x = r * c + root
    v = -r * omega * s - r * r * omega * s * c / root
    acc = (-r * omega**2 * c - r * r * omega**2 * (c * c - s * s) / root
           - r**4 * omega**2 * s * s * c * c / root**3)
    lam = r / l
    q = math.sqrt(1.0 - (lam * s) ** 2)
    phi = -math.asin(lam * s)
    phi_d = -lam * omega * c / q
    phi_dd = lam * omega**2 * s / q - lam**3 * omega**2 * s * c * c / q**3
    # A's acceleration -r ω² (cos θ, sin θ), projected on e = (cos φ, sin φ) and n = (-sin φ, cos φ)
    ax, ay = -r * omega**2 * c, -r * omega**2 * s
    cp, sp = math.cos(phi), math.sin(phi)
    return th, x, v, acc, phi, phi_d, phi_dd, ax * cp + ay * sp, -ax * sp + ay * cp


@njit(cache=True)
def _rigid_table(r: float, l: float, omega: float, t: np.ndarray) -> np.ndarray:
    out = np.empty((9, t.shape[0]))
    for i in range(t.shape[0]):
        state = rigid_state(r, l, omega, t[i])
        for k in range(9):
            out[k, i] = state[k]
    return out


def rigid_motion(r: float, l: float, omega: float, t: np.ndarray) -> RigidMotion:
    """Rigid kinematics of the in-line slider-crank.

    Parameters
    ----------
    r, l : float
        Crank and rod lengths (m), l > r.
    omega : float
        Constant crank rate (rad/s); θ = ω t.
    t : ndarray
        Times (s).

    Returns
    -------
    RigidMotion
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    th, x, v, acc, phi, phi_d, phi_dd, a_par, a_perp = _rigid_table(float(r), float(l), float(omega), t)
    return RigidMotion(t=t, theta=th, x=x, v=v, acc=acc, phi=phi, phi_d=phi_d, phi_dd=phi_dd,
                       aA_par=a_par, aA_perp=a_perp)
