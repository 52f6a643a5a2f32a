"""Paper 000's error E (Eq. 11) of a design: closest points on both branches, the better branch kept.

One "simulation" of a design: its coupler curve over a full crank revolution on both assembly branches K = ±1, the
closest point of each to every desired point (:mod:`.closest_point`, unprescribed timing: each point's crank angle
free), and the branch with the smaller sum of squared distances.  All points on one branch avoid the branch defect
(paper §2.1.1).  The residual vector holds the signed distances r_i (+ where the desired point lies left of the
curve's direction of travel), so that E = Σ r_i².
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechopt.sim.path_synthesis.closest_point import DEFAULT_GRID, closest_points
from mechopt.sim.path_synthesis.coupler import BRANCHES

__all__ = ["PathFit", "fit_path"]


@dataclass(frozen=True)
class PathFit:
    """A design's fit to the desired points on its better branch.

    Attributes
    ----------
    E : float
        Eq. 11: the plain sum of squared distances (length²).
    branch : int
        The branch K (±1) of the smaller E.
    phi : (N,) ndarray
        Crank angle of each closest point (rad, in [0, 2π)).
    residuals : (N,) ndarray
        Signed distances (length), E = Σ residuals².
    E_other : float
        E on the other branch.
    """

    E: float
    branch: int
    phi: np.ndarray
    residuals: np.ndarray
    E_other: float

    @property
    def distances(self) -> np.ndarray:
        """Unsigned distances |r_i| (length)."""
        return np.abs(self.residuals)


def fit_path(design: np.ndarray, points: np.ndarray, n_grid: int = DEFAULT_GRID,
             branches: tuple[int, ...] = BRANCHES) -> PathFit:
    """Closest points of a design's coupler curve to the desired points, on the better of ``branches``.

    Parameters
    ----------
    design : (8,) array_like
        (a1, ..., a8) of :mod:`.coupler`; its crank should turn fully (not checked here).
    points : (N, 2) array_like
        Desired points (lengths).
    n_grid : int
        Crank angles sampled before the refinement.
    branches : tuple of int
        The branches tried (default both).

    Returns
    -------
    PathFit
    """
    fits = []
    for k in branches:
        phi, d2, side = closest_points(design, points, k, n_grid)
        fits.append((float(np.sum(d2)), k, phi, side * np.sqrt(d2)))
    fits.sort(key=lambda f: f[0])
    E, k, phi, r = fits[0]
    return PathFit(E=E, branch=int(k), phi=phi, residuals=r, E_other=fits[1][0] if len(fits) > 1 else float("nan"))
