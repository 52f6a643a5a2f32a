"""The continuous variables of a design polished with its discrete ones held: how the default method rounds a
relaxed optimum when a problem mixes discrete and continuous variables.

The acquisition (or the model's mean) is first maximised as if every variable were continuous; its optimum then
lies between allowed values, often on a declared constraint.  Rounding the discrete variables with the continuous
ones kept leaves that constraint: on Sandgren's coil spring one coil fewer needs a larger coil diameter to keep its
deflection, so the rounded design is infeasible and the neighbour left standing has a diameter far from its own
best.  Each discrete neighbour of the relaxed optimum is therefore given its own best continuous values (SLSQP on
the declared constraints' margins, else L-BFGS-B) before the neighbours are compared: BoTorch's
``optimize_acqf_mixed`` over fixed features, restricted to the neighbours of the relaxation.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.optimize import minimize

from mechopt.optimize.auto.design_grid import DesignGrid

__all__ = ["MOST_NEIGHBOURS", "held_maximise", "polished_neighbours"]

#: Discrete neighbours of a relaxed optimum whose continuous variables are polished (the nearest ones first).
MOST_NEIGHBOURS = 27
#: Margin kept from a declared constraint (the margins' units).  It is all an answer on an active constraint loses:
#: 1e-7 (the relaxed polish's) left the coil spring 3e-6 % above its best known value, where SMT's EGO ends 1e-7 %.
_MARGIN_EPS = 1e-10


def held_maximise(score: Callable[[np.ndarray], np.ndarray], x: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                  free: np.ndarray, margins: Callable[[np.ndarray], np.ndarray] | None = None,
                  maxiter: int = 30) -> np.ndarray:
    """``x`` (unit cube) with its ``free`` coordinates moved to maximise ``score`` in [lo, hi], the others held.

    Parameters
    ----------
    score : callable
        ``score(U) -> (m,)`` to maximise, at designs U (m, d) of the unit cube.
    x : (d,) ndarray
        Start; its held coordinates are kept exactly.
    lo, hi : (d,) ndarray
        Box of the free coordinates.
    free : (d,) bool ndarray
        The coordinates that move (the continuous variables).
    margins : callable, optional
        ``margins(U) -> (m, c)`` of the declared constraints (>= 0 feasible): SLSQP keeps them, else L-BFGS-B.
    maxiter : int
        Iterations of the local optimiser.

    Returns
    -------
    (d,) ndarray
        The polished design (``x`` itself when no coordinate is free).
    """
    idx = np.flatnonzero(free)
    x = np.array(x, dtype=float)
    if not idx.size:
        return x
    lo_f, hi_f = lo[idx], hi[idx]
    h = 1e-6 * np.maximum(hi_f - lo_f, 1e-12)

    def full(v: np.ndarray) -> np.ndarray:
        u = x.copy()
        u[idx] = v
        return u

    def stepped(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # Forward differences in the free coordinates only, from one batched call (inwards at an upper bound).
        step = np.where(v + h <= hi_f, h, -h)
        P = np.repeat(full(v)[None, :], idx.size + 1, axis=0)
        P[1 + np.arange(idx.size), idx] += step
        return P, step

    def fun(v: np.ndarray) -> tuple[float, np.ndarray]:
        P, step = stepped(v)
        s = -score(P)
        if not np.all(np.isfinite(s)):
            return 1e300, np.zeros(idx.size)
        return float(s[0]), (s[1:] - s[0]) / step

    def margins_jac(v: np.ndarray) -> np.ndarray:
        P, step = stepped(v)
        M = margins(P)
        return ((M[1:] - M[0]) / step[:, None]).T

    bounds = list(zip(lo_f, hi_f, strict=True))
    v0 = np.clip(x[idx], lo_f, hi_f)
    if margins is None:
        res = minimize(fun, v0, jac=True, method="L-BFGS-B", bounds=bounds, options={"maxiter": maxiter})
    else:
        res = minimize(fun, v0, jac=True, method="SLSQP", bounds=bounds, options={"maxiter": maxiter},
                       constraints=[{"type": "ineq", "fun": lambda v: margins(full(v)[None, :])[0] - _MARGIN_EPS,
                                     "jac": margins_jac}])
    return full(np.clip(res.x, lo_f, hi_f))


def polished_neighbours(score: Callable[[np.ndarray], np.ndarray], grid: DesignGrid, X: np.ndarray,
                        lo: np.ndarray, hi: np.ndarray, radius: int,
                        margins: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """The allowed designs around relaxed optima ``X`` (k, d): each distinct setting of the discrete variables up to
    ``radius`` allowed values from one of them (the :data:`MOST_NEIGHBOURS` nearest), with the continuous variables
    of the relaxed optimum it came from kept, and the same with them polished by :func:`held_maximise`; (m, d), not
    yet tested for being allowed."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    N = np.vstack([grid.neighbourhood(x, radius=radius) for x in X])
    free = ~grid.mask
    if not free.any():
        return N
    # Several relaxed optima usually round to the same discrete settings: each setting is polished once.
    _, first = np.unique(N[:, grid.mask], axis=0, return_index=True)
    N = N[np.sort(first)]
    if N.shape[0] > MOST_NEIGHBOURS:
        near = np.min(np.sum((N[:, None, :] - X[None, :, :]) ** 2, axis=2), axis=1)
        N = N[np.sort(np.argsort(near, kind="stable")[:MOST_NEIGHBOURS])]
    P = np.array([held_maximise(score, n, lo, hi, free, margins) for n in N])
    return np.vstack([N, P])
