"""What a flexible four-bar simulation returns, and the paper's five-term error (Eq. 25).

Eq. 25 is garbled in print (its last term repeats a dozen times); read as five unweighted terms, each the RMS over
the N instants of the difference to the target normalised by the candidate response's own range (Eq. 18):

    f = f_cr + f_co + f_fo + f(D3) + f(D4),   f_k = sqrt(1/N Σ_i [(Δx_i / R_x)² + (Δy_i / R_y)²]) for a path,

with R_x = max x − min x of the candidate's path, i.e. f_k = sqrt(f(x)² + f(y)²) in terms of Eq. 18.
:func:`residuals` spells each term out instant by instant (least squares): f_k = sqrt(Σ r²) over its residuals.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechopt.sim.flexible_slider_crank.response import normalised_error, normalised_residuals

__all__ = ["PATHS", "TERMS", "FourBarResponse", "five_term_error", "path_error", "residuals"]

#: The mid-point paths of Eq. 25, by the link they belong to.
PATHS = ("crank", "coupler", "follower")
#: Names of the five terms of Eq. 25, in its order.
TERMS = ("f_crank", "f_coupler", "f_follower", "f_D3", "f_D4")


@dataclass(frozen=True)
class FourBarResponse:
    """Responses of one design at the paper's instants (SI units).

    Attributes
    ----------
    t : ndarray (n,)
        Sample times (s).
    crank, coupler, follower : ndarray (n, 2)
        Paths (x, y) of the links' mid-points (m), elastic deflection included for the flexible links.
    D3, D4 : ndarray (n,)
        Deflection of the coupler's and the follower's mid-point from their chord (m), positive along the chord's
        +90° normal (the paper's "mid-point axial displacement", read as in its slider-crank case).
    s3, s4 : ndarray
        Arc lengths (m) from B and from O4 at which ``shape3``, ``shape4`` are given.
    shape3, shape4 : ndarray (n, len(s))
        Deflection of each link from its chord (m), for drawings.
    engine : str
        ``"modal"`` or ``"exudyn"``.
    seconds : float
        Wall time of the simulation (s).
    """

    t: np.ndarray
    crank: np.ndarray
    coupler: np.ndarray
    follower: np.ndarray
    D3: np.ndarray
    D4: np.ndarray
    s3: np.ndarray
    s4: np.ndarray
    shape3: np.ndarray
    shape4: np.ndarray
    engine: str
    seconds: float


def path_error(P: np.ndarray, P_target: np.ndarray) -> float:
    """One path term of Eq. 25: sqrt(f(x)² + f(y)²) with f the normalised error of Eq. 18 (dimensionless)."""
    P = np.asarray(P, dtype=float)
    P_target = np.asarray(P_target, dtype=float)
    return float(np.hypot(normalised_error(P[:, 0], P_target[:, 0]), normalised_error(P[:, 1], P_target[:, 1])))


def five_term_error(r: FourBarResponse, target: FourBarResponse) -> dict[str, float]:
    """The five terms of Eq. 25 and their sum ``f`` (all dimensionless)."""
    out = {f"f_{k}": path_error(getattr(r, k), getattr(target, k)) for k in PATHS}
    out["f_D3"] = normalised_error(r.D3, target.D3)
    out["f_D4"] = normalised_error(r.D4, target.D4)
    out["f"] = float(sum(out[k] for k in TERMS))
    return out


def residuals(r: FourBarResponse, target: FourBarResponse) -> np.ndarray:
    """The residuals of Eq. 25, term after term in the order of :data:`TERMS`.

    A path contributes its x then its y residuals, (x_i − x*_i) / (R_x sqrt(N)) (2N values), D3 and D4 N values
    each (:func:`~mechopt.sim.flexible_slider_crank.response.normalised_residuals`): the square root of a
    term's sum of squares is that term of :func:`five_term_error`, so f = 0 exactly where every residual is 0.

    Returns
    -------
    ndarray (8 N,)
        Dimensionless.
    """
    parts = [normalised_residuals(getattr(r, k)[:, j], getattr(target, k)[:, j]) for k in PATHS for j in (0, 1)]
    parts += [normalised_residuals(r.D3, target.D3), normalised_residuals(r.D4, target.D4)]
    return np.concatenate(parts)
