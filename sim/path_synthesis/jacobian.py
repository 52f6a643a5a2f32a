"""The Jacobian of a design's residuals with respect to a1..a8, exact, by the envelope theorem at the closest points.

The residual r_i = ±|P(φ_i*, a) − D_i| is a distance minimised over φ, so its derivative needs no dφ_i*/da:
∂r_i/∂a = −n_i · ∂P/∂a at φ_i*, where n_i is the unit left normal of the curve there (the sign convention of
:mod:`.path_error`: r_i > 0 when D_i lies left of the direction of travel).  It holds wherever the closest point is
unique and the curve regular there; it is one closed-form evaluation instead of eight finite differences.
"""

from __future__ import annotations

import math

import numpy as np

from mechopt.sim.path_synthesis.coupler import coupler_point_derivatives
from mechopt.sim.path_synthesis.path_error import PathFit

__all__ = ["coupler_point_gradient", "residual_jacobian"]


def coupler_point_gradient(design: np.ndarray, phi: np.ndarray, branch: int) -> np.ndarray:
    """∂P/∂a_j of the coupler point at fixed crank angles, (n, 2, 8).

    Parameters
    ----------
    design : (8,) array_like
        (a1, ..., a8).
    phi : (n,) array_like
        Crank angles (rad).
    branch : int
        K = ±1.
    """
    a1, a2, a3, a4, a5, a6 = (float(v) for v in np.asarray(design, dtype=float)[:6])
    phi = np.atleast_1d(np.asarray(phi, dtype=float))
    s, co = np.sin(phi), np.cos(phi)
    u = (a5 - a1 * s) / a2
    c = branch * np.sqrt(np.clip(1.0 - u * u, 0.0, None))
    dc_du = -u / np.where(c == 0.0, np.nan, c)
    du = {"a1": -s / a2, "a2": -u / a2, "a5": np.full_like(u, 1.0 / a2)}
    zero = np.zeros_like(u)
    local = np.zeros((phi.size, 2, 8))
    for j, name in enumerate(("a1", "a2", "a3", "a4", "a5")):
        d_u = du.get(name, zero)
        d_c = dc_du * d_u
        dx = a3 * d_c - a4 * d_u + (co if name == "a1" else 0.0) + (c if name == "a3" else 0.0) - \
            (u if name == "a4" else 0.0)
        dy = (a3 - a2) * d_u + a4 * d_c + (u if name == "a3" else 0.0) - (u if name == "a2" else 0.0) + \
            (c if name == "a4" else 0.0) + (1.0 if name == "a5" else 0.0)
        local[:, 0, j], local[:, 1, j] = dx, dy
    ca, sa = math.cos(a6), math.sin(a6)
    rot = np.array([[ca, -sa], [sa, ca]])
    grad = np.einsum("ik,nkj->nij", rot, local)
    xl = a1 * co + a3 * c - a4 * u
    yl = (a3 - a2) * u + a5 + a4 * c
    grad[:, 0, 5], grad[:, 1, 5] = -xl * sa - yl * ca, xl * ca - yl * sa
    grad[:, 1, 6] = 1.0
    grad[:, 0, 7] = 1.0
    return grad


def residual_jacobian(design: np.ndarray, fit: PathFit) -> np.ndarray:
    """∂r_i/∂a_j of a design's residuals at its fit (the closest points and branch of :func:`.path_error.fit_path`).

    Parameters
    ----------
    design : (8,) array_like
        (a1, ..., a8), the design ``fit`` was computed for.
    fit : PathFit
        Its closest points.

    Returns
    -------
    (N, 8) ndarray
        One row per desired point.  NaN where the curve is not regular at the closest point (a dead point of the
        rod on the Grashof boundary).
    """
    a = np.ascontiguousarray(design, dtype=float)
    tangents = np.array([coupler_point_derivatives(a, fit.branch, float(p))[2:4] for p in fit.phi])
    norm = np.linalg.norm(tangents, axis=1, keepdims=True)
    left = np.column_stack([-tangents[:, 1], tangents[:, 0]]) / np.where(norm == 0.0, np.nan, norm)
    return -np.einsum("nk,nkj->nj", left, coupler_point_gradient(a, fit.phi, fit.branch))
