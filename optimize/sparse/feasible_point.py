"""Moving a design back into the feasible region: the one routine every stage uses."""

from __future__ import annotations

import numpy as np

from mechopt.optimize.sparse.space import ModelSpace

__all__ = ["pull_into_feasible"]


def pull_into_feasible(space: ModelSpace, design: np.ndarray, anchors: np.ndarray, steps: int = 50) -> np.ndarray:
    """``design`` if feasible, else the feasible point nearest to it on the segment to the nearest feasible anchor.

    Parameters
    ----------
    space : ModelSpace
        The problem's predicates.
    design : (d,) ndarray
        A design, e.g. a model's minimum found with a coarser feasibility screen.
    anchors : (n, d) ndarray
        Known designs (samples); the feasible ones are candidates to move towards.
    steps : int
        Bisection steps along the segment.

    Returns
    -------
    (d,) ndarray
        A feasible design (``design`` itself when no anchor is feasible and it is not: the caller checks).
    """
    design = np.asarray(design, dtype=float)
    if space.feasible(design)[0]:
        return design
    pool = np.atleast_2d(np.asarray(anchors, dtype=float))
    pool = pool[space.feasible(pool)] if pool.size else pool
    if not len(pool):
        return design
    anchor = pool[np.argmin(np.linalg.norm(pool - design, axis=1))]
    # Bisection on the segment: the feasible end moves towards the design as far as feasibility allows.
    lo, hi = 0.0, 1.0
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        if space.feasible(design + mid * (anchor - design))[0]:
            hi = mid
        else:
            lo = mid
    return design + hi * (anchor - design)
