"""The closest point of a design's coupler curve (one full crank revolution) to each desired point.

For one branch K the curve is sampled on a grid of ``n_grid`` crank angles; for each desired point the best grid
angle and the best other local minimum of the sampled squared distance are refined, each by Newton steps on
g(φ) = (P − D)·P' = ½ d|P − D|²/dφ, safeguarded by bisection inside ±one grid step, and the smaller is kept: the
distance is then exact to ~1e-12 (the step stops below 1e-13 rad).  This is paper 000's first phase (its Fig. 4-5:
the minimum over [0, 2π) of each point's error, then ``fsolve`` on Eq. 13), done by a numba kernel in ~10 µs a
branch for 25 points.

A design whose crank cannot turn fully is searched on the clipped continuation of :mod:`.coupler`; callers check
the margins first (:mod:`.feasibility`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from mechopt.sim.path_synthesis.coupler import coupler_point_derivatives

__all__ = ["DEFAULT_GRID", "closest_points"]

#: Grid of crank angles searched before the refinement (a step of 1°).
DEFAULT_GRID = 360


@njit(cache=True)
def _g(design, branch, phi, dx, dy):
    x, y, xp, yp, xpp, ypp = coupler_point_derivatives(design, branch, phi)
    ex, ey = x - dx, y - dy
    return ex * xp + ey * yp, xp * xp + yp * yp + ex * xpp + ey * ypp, ex * ex + ey * ey


@njit(cache=True)
def _refine(design, branch, phi0, f0, h, dx, dy):
    """Safeguarded Newton on g inside [φ0 − h, φ0 + h]; returns the best (φ, d²) seen, never worse than φ0."""
    lo, hi = phi0 - h, phi0 + h
    best_phi, best_f = phi0, f0
    phi = phi0
    for _ in range(60):
        g, dg, f = _g(design, branch, phi, dx, dy)
        if f < best_f:
            best_phi, best_f = phi, f
        if g > 0.0:
            hi = phi
        else:
            lo = phi
        step = g / dg if (dg > 0.0 and math.isfinite(dg) and math.isfinite(g)) else math.inf
        new = phi - step
        if not (lo < new < hi):
            new = 0.5 * (lo + hi)
        if abs(new - phi) < 1e-13:
            break
        phi = new
    return best_phi, best_f


@njit(cache=True)
def _closest_kernel(design, branch, px, py, n_grid, phi_out, d2_out, side_out):
    h = 2.0 * math.pi / n_grid
    gx = np.empty(n_grid)
    gy = np.empty(n_grid)
    for j in range(n_grid):
        x, y, _, _, _, _ = coupler_point_derivatives(design, branch, j * h)
        gx[j], gy[j] = x, y
    d = np.empty(n_grid)
    for i in range(px.size):
        for j in range(n_grid):
            d[j] = (gx[j] - px[i]) ** 2 + (gy[j] - py[i]) ** 2
        k1, k2 = -1, -1
        for j in range(n_grid):
            if d[j] <= d[j - 1] and d[j] <= d[(j + 1) % n_grid]:
                if k1 < 0 or d[j] < d[k1]:
                    k2, k1 = k1, j
                elif k2 < 0 or d[j] < d[k2]:
                    k2 = j
        best_phi, best_f = _refine(design, branch, k1 * h, d[k1], h, px[i], py[i])
        if k2 >= 0:
            phi2, f2 = _refine(design, branch, k2 * h, d[k2], h, px[i], py[i])
            if f2 < best_f:
                best_phi, best_f = phi2, f2
        best_phi = best_phi % (2.0 * math.pi)
        x, y, xp, yp, _, _ = coupler_point_derivatives(design, branch, best_phi)
        phi_out[i], d2_out[i] = best_phi, (x - px[i]) ** 2 + (y - py[i]) ** 2
        # which side of the curve's direction of travel the desired point lies on: +1 left, −1 right
        side_out[i] = 1.0 if xp * (py[i] - y) - yp * (px[i] - x) >= 0.0 or not math.isfinite(xp + yp) else -1.0


def closest_points(design: np.ndarray, points: np.ndarray, branch: int, n_grid: int = DEFAULT_GRID
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Crank angle, squared distance and side of the closest coupler-curve point to each desired point.

    Parameters
    ----------
    design : (8,) array_like
        (a1, ..., a8) of :mod:`.coupler`.
    points : (N, 2) array_like
        Desired points (x, y), lengths.
    branch : int
        K = ±1.
    n_grid : int
        Crank angles sampled before the refinement (default 360).

    Returns
    -------
    phi : (N,) ndarray
        Crank angle of each closest point, in [0, 2π) (rad).
    d2 : (N,) ndarray
        Squared distances (length²); their sum is Eq. 11's E on this branch.
    side : (N,) ndarray
        +1 where the desired point lies left of the curve's direction of travel (increasing φ), −1 right.
    """
    a = np.ascontiguousarray(design, dtype=float)
    pts = np.asarray(points, dtype=float)
    n = pts.shape[0]
    phi, d2, side = np.empty(n), np.empty(n), np.empty(n)
    _closest_kernel(a, int(branch), np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1]), int(n_grid),
                    phi, d2, side)
    return phi, d2, side
