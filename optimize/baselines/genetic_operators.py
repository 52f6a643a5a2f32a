"""The variation operators of a real-coded genetic algorithm on the unit cube: simulated binary crossover and
polynomial mutation (Deb & Agrawal 1995; Deb & Goyal 1996; Deb 2001), as paper 000's hybrid
(:mod:`~mechopt.optimize.baselines.paper000_hybrid`) breeds its children.  A plain GA is pymoo's
(:func:`~mechopt.optimize.baselines.pymoo_algorithms.minimize_pymoo_ga`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["polynomial_mutation", "sbx_crossover"]


def sbx_crossover(
    a: np.ndarray, b: np.ndarray, rng: np.random.Generator, *, eta: float = 15.0
) -> tuple[np.ndarray, np.ndarray]:
    """Simulated binary crossover of two parents in the unit cube (bounded form of Deb & Agrawal 1995).

    Parameters
    ----------
    a, b : ndarray, shape (d,)
        Parents in ``[0, 1]^d``.
    rng : numpy.random.Generator
    eta : float, default 15
        Distribution index; larger keeps children closer to the parents.

    Returns
    -------
    tuple of ndarray
        Two children in ``[0, 1]^d``; each variable is crossed with probability 1/2.
    """
    c1, c2 = a.copy(), b.copy()
    for i in range(a.size):
        if rng.random() > 0.5 or abs(a[i] - b[i]) < 1e-14:
            continue
        y1, y2 = min(a[i], b[i]), max(a[i], b[i])
        u = rng.random()
        children = []
        # The spread factor's tail is cut at each bound so children never leave [0, 1] (bounded SBX).
        for distance in (y1, 1.0 - y2):
            beta = 1.0 + 2.0 * distance / (y2 - y1)
            alpha = 2.0 - beta ** -(eta + 1.0)
            if u <= 1.0 / alpha:
                betaq = (u * alpha) ** (1.0 / (eta + 1.0))
            else:
                betaq = (1.0 / (2.0 - u * alpha)) ** (1.0 / (eta + 1.0))
            children.append(betaq)
        lo = 0.5 * ((y1 + y2) - children[0] * (y2 - y1))
        hi = 0.5 * ((y1 + y2) + children[1] * (y2 - y1))
        lo, hi = float(np.clip(lo, 0.0, 1.0)), float(np.clip(hi, 0.0, 1.0))
        if rng.random() < 0.5:
            lo, hi = hi, lo
        c1[i], c2[i] = lo, hi
    return c1, c2


def polynomial_mutation(
    u: np.ndarray, rng: np.random.Generator, *, eta: float = 20.0, probability: float | None = None
) -> np.ndarray:
    """Bounded polynomial mutation (Deb & Goyal 1996) of a design in the unit cube.

    Parameters
    ----------
    u : ndarray, shape (d,)
        Design in ``[0, 1]^d``.
    rng : numpy.random.Generator
    eta : float, default 20
        Distribution index; larger gives smaller perturbations.
    probability : float, optional
        Per-variable mutation probability, default ``1 / d``.

    Returns
    -------
    ndarray, shape (d,)
        Mutated copy, still in ``[0, 1]^d``.
    """
    out = u.copy()
    pm = 1.0 / u.size if probability is None else probability
    for i in range(u.size):
        if rng.random() >= pm:
            continue
        y = out[i]
        r = rng.random()
        power = 1.0 / (eta + 1.0)
        if r < 0.5:
            xy = 1.0 - y  # 1 - delta1, delta1 = y being the distance to the lower bound
            val = 2.0 * r + (1.0 - 2.0 * r) * xy ** (eta + 1.0)
            dq = val**power - 1.0
        else:
            xy = y  # 1 - delta2, delta2 = 1 - y being the distance to the upper bound
            val = 2.0 * (1.0 - r) + 2.0 * (r - 0.5) * xy ** (eta + 1.0)
            dq = 1.0 - val**power
        out[i] = float(np.clip(y + dq, 0.0, 1.0))
    return out
