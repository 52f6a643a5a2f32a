"""Where to start the next local search: multi-level single linkage (Rinnooy Kan & Timmer 1987).

A sampled design starts a local search when no better sampled design lies within the critical distance r_N and no
earlier search passed within r_N of it.  r_N shrinks as the sample grows, so every basin is eventually entered
once and, with probability one, no basin twice: the global phase of a least-squares problem needs no model of the
objective, only a growing uniform sample and a good local solver.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["critical_distance", "choose_starts"]

#: MLSL's sigma: > 2 guarantees finitely many local searches (Rinnooy Kan & Timmer, Theorem 8); 4 is the usual value.
SIGMA = 4.0


def critical_distance(n: int, dim: int, sigma: float = SIGMA) -> float:
    """r_N = π^(-1/2) (Γ(1 + d/2) σ log N / N)^(1/d) in the unit cube of ``dim`` variables, ``n`` sampled designs."""
    n = max(int(n), 2)
    return float((math.gamma(1.0 + dim / 2.0) * sigma * math.log(n) / n) ** (1.0 / dim) / math.sqrt(math.pi))


def choose_starts(U: np.ndarray, values: np.ndarray, explored: np.ndarray, radius: float,
                  limit: int) -> np.ndarray:
    """Indices of sampled designs to start local searches from, best first.

    Parameters
    ----------
    U : (n, d) ndarray
        Sampled designs (unit cube).
    values : (n,) ndarray
        Their objective (NaN or inf: failed, never a start).
    explored : (k, d) ndarray
        Designs earlier local searches visited.
    radius : float
        Critical distance r_N.
    limit : int
        Most starts returned.

    Returns
    -------
    ndarray of int
    """
    ok = np.isfinite(values)
    order = np.argsort(np.where(ok, values, np.inf))
    order = order[ok[order]]
    tree = cKDTree(U[order]) if order.size else None
    near_explored = (cKDTree(explored).query(U[order], distance_upper_bound=radius)[0] <= radius
                     if explored.shape[0] and order.size else np.zeros(order.size, dtype=bool))
    chosen: list[int] = []
    for rank, i in enumerate(order):
        if len(chosen) >= limit:
            break
        if near_explored[rank]:
            continue
        better = tree.query_ball_point(U[i], radius)
        if any(j < rank for j in better):
            continue
        chosen.append(int(i))
    return np.array(chosen, dtype=int)
