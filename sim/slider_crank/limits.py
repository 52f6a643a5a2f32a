"""Limit positions (dead centres), stroke and time ratio of a slider-crank whose crank turns fully, in closed form.

At the two dead centres the crank and the rod are aligned (paper 001, Fig. 1, Eqs. 1–6): extended, A between O and
B, with |OB| = l + r; folded, O between A and B, with |OB| = l − r.  On the line y = h
the slider then stands at x_e = √((l + r)² − h²) and x_f = √((l − r)² − h²) (branch +1), so

    S = x_e − x_f,   ψ = asin(h/(l − r)) − asin(h/(l + r)),   TR = (180° + |ψ|) / (180° − |ψ|),

ψ being the angle B1-O-B2 of paper 001 (its Eq. 3 with cos⁻¹, identical), the crank turning π ± ψ between the
dead centres.  Everything is vectorised over designs; lengths in one unit (mm at the public surface), angles in rad.
NaN where the crank cannot turn fully (r + |h| > l).
"""

from __future__ import annotations

import numpy as np

from mechopt.sim.slider_crank.kinematics import BRANCH_RIGHT, check_branch


def _arrays(r, l, h):
    r, l, h = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (r, l, h)))
    full = (r > 0) & (l - r - np.abs(h) >= 0.0)
    return r, l, h, full


def limit_positions(r: np.ndarray | float, l: np.ndarray | float, h: np.ndarray | float,
                    branch: int = BRANCH_RIGHT) -> dict[str, np.ndarray]:
    """Crank angles and slider positions at the extended and folded dead centres.

    Parameters
    ----------
    r, l, h : array_like
        Crank, rod and offset (mm).
    branch : int
        +1: slider on the +x side of the crank pin; −1: the mirror image.

    Returns
    -------
    dict
        ``theta_extended``, ``theta_folded`` (rad, in [−π, 2π)) and ``x_extended``, ``x_folded`` (mm); NaN where
        the crank cannot turn fully.
    """
    branch = check_branch(branch)
    r, l, h, full = _arrays(r, l, h)
    with np.errstate(invalid="ignore"):
        xe = np.where(full, np.sqrt(np.maximum((l + r) ** 2 - h**2, 0.0)), np.nan)
        xf = np.where(full, np.sqrt(np.maximum((l - r) ** 2 - h**2, 0.0)), np.nan)
    th_e = np.arctan2(h, xe)
    th_f = np.arctan2(h, xf) + np.pi
    if branch == -1:
        # Mirror image in the y axis: x → −x, θ → π − θ.
        xe, xf, th_e, th_f = -xe, -xf, np.pi - th_e, np.pi - th_f
    return {"theta_extended": th_e, "theta_folded": th_f, "x_extended": xe, "x_folded": xf}


def stroke(r: np.ndarray | float, l: np.ndarray | float, h: np.ndarray | float) -> np.ndarray:
    """Stroke S = √((l + r)² − h²) − √((l − r)² − h²) (paper 001, Eq. 1), in the unit of the lengths."""
    lim = limit_positions(r, l, h)
    return np.abs(lim["x_extended"] - lim["x_folded"])


def dead_centre_angle(r: np.ndarray | float, l: np.ndarray | float, h: np.ndarray | float) -> np.ndarray:
    """Angle ψ = ∠B1OB2 = asin(h/(l − r)) − asin(h/(l + r)) (rad) between the dead centres (paper 001, Eq. 3)."""
    r, l, h, full = _arrays(r, l, h)
    with np.errstate(invalid="ignore", divide="ignore"):
        psi = np.arcsin(np.clip(h / (l - r), -1, 1)) - np.arcsin(np.clip(h / (l + r), -1, 1))
    return np.where(full, psi, np.nan)


def time_ratio(r: np.ndarray | float, l: np.ndarray | float, h: np.ndarray | float) -> np.ndarray:
    """Time ratio TR = (π + |ψ|)/(π − |ψ|) >= 1 at constant crank speed (paper 001, Eqs. 4–6), dimensionless."""
    psi = np.abs(dead_centre_angle(r, l, h))
    return (np.pi + psi) / (np.pi - psi)
