"""Shuffled complex evolution, SCE-UA (Duan, Sorooshian & Gupta 1992; Duan et al. 1994), run to the budget.

Best method of paper 004's comparison of seven metaheuristics.  ``p`` complexes of ``m`` points each evolve
independently by competitive complex evolution (CCE): a sub-complex of ``q`` points is drawn with trapezoidal
(rank-based) probabilities, its worst point is reflected through the centroid of the others, contracted halfway
when the reflection does not improve, and replaced by a random point of the complex's smallest enclosing box when
neither does; after ``beta`` such steps the complexes are shuffled (pooled, sorted and dealt again).

Constraint handling: rejection, as in Duan's "feasible space".  The initial points are feasible (cheap rejection
sampling); a reflection or contraction that leaves the feasible region is not simulated but replaced by a random
feasible point of the complex's enclosing box, so the simulator only sees feasible designs.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.errors import InputError
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["minimize_sce_ua"]


def _random_in_box(problem: CountedProblem, lo: np.ndarray, hi: np.ndarray, rng: np.random.Generator,
                   tries: int = 200) -> np.ndarray | None:
    """Uniform random feasible design in the box [lo, hi] (rejection), None when none is hit."""
    for _ in range(tries):
        z = lo + rng.random(lo.size) * (hi - lo)
        if problem.feasible(z)[0]:
            return z
    return None


def minimize_sce_ua(
    problem: CountedProblem,
    seed: int,
    *,
    n_complexes: int = 2,
    complex_size: int | None = None,
    subcomplex_size: int | None = None,
    n_evolution_steps: int | None = None,
    alpha: int = 1,
    peps: float = 1e-6,
) -> OptimizeResult:
    """SCE-UA until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the sampling and of the CCE draws.
    n_complexes : int, default 2
        ``p``; paper 004 uses 2 complexes.
    complex_size : int, optional
        ``m``, default ``2 d + 1`` (Duan et al. 1994).
    subcomplex_size : int, optional
        ``q``, default ``d + 1``.
    n_evolution_steps : int, optional
        ``beta``, CCE steps per complex between shuffles, default ``m``.
    alpha : int, default 1
        Offspring generated per sub-complex.
    peps : float, default 1e-6
        Duan's convergence test: when every variable's range over the population is below ``peps`` of the box
        width, the population has collapsed; it is then re-sampled (keeping its best point) so the rest of the
        budget explores instead of re-proposing one design.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nshuffles``,
        ``nrestarts`` (population collapses).
    """
    rng = np.random.default_rng(seed)
    d = problem.dim
    m = 2 * d + 1 if complex_size is None else int(complex_size)
    q = d + 1 if subcomplex_size is None else int(subcomplex_size)
    beta = m if n_evolution_steps is None else int(n_evolution_steps)
    p = int(n_complexes)
    if not 2 <= q <= m:
        raise InputError(f"need 2 <= subcomplex_size <= complex_size, got q={q}, m={m}")
    s = p * m
    points = _initial_points(problem, s, rng)
    if points is None:
        return problem.result("no feasible initial point found", nshuffles=0, nrestarts=0)

    # Trapezoidal selection probabilities of Duan et al.: rank 1 (best) is the most likely.
    ranks = np.arange(1, m + 1)
    weights = 2.0 * (m + 1 - ranks) / (m * (m + 1))
    n_shuffles = n_restarts = 0
    try:
        values = np.array([_value(problem, x) for x in points])
        while True:
            order = np.argsort(values, kind="stable")
            points, values = points[order], values[order]
            if np.all(np.ptp(points, axis=0) < peps * problem.span):
                fresh = _initial_points(problem, s, rng)
                if fresh is None:
                    return problem.result("population converged, no feasible point to restart from",
                                          nshuffles=n_shuffles, nrestarts=n_restarts)
                fresh[0] = points[0]
                points, values = fresh, np.array([_value(problem, x) for x in fresh])
                n_restarts += 1
                continue
            for k in range(p):
                # Dealing sorted points round-robin gives every complex a share of the whole range.
                idx = np.arange(k, s, p)
                points[idx], values[idx] = _evolve_complex(problem, points[idx].copy(), values[idx].copy(), rng,
                                                           weights, q=q, beta=beta, alpha=alpha)
            n_shuffles += 1
    except BudgetExhausted as exc:
        return problem.result(str(exc), nshuffles=n_shuffles, nrestarts=n_restarts)


def _initial_points(problem: CountedProblem, s: int, rng: np.random.Generator) -> np.ndarray | None:
    """``s`` feasible designs (Latin hypercube, rejection), None when none is found."""
    found = problem.sample_feasible(s, rng)
    if found.shape[0] == 0:
        return None
    if found.shape[0] < s:
        # A tiny feasible region: repeat found points rather than give up (repeats are cached, not re-simulated).
        found = found[rng.integers(found.shape[0], size=s)]
    return found


def _value(problem: CountedProblem, x: np.ndarray) -> float:
    """Simulated objective of a feasible design, a failed simulation ranked last (+inf)."""
    f = problem.evaluate(x)
    return f if math.isfinite(f) else math.inf


def _evolve_complex(problem: CountedProblem, cx: np.ndarray, cf: np.ndarray, rng: np.random.Generator,
                    weights: np.ndarray, *, q: int, beta: int, alpha: int) -> tuple[np.ndarray, np.ndarray]:
    """Competitive complex evolution: ``beta`` steps on one complex (points ``cx``, values ``cf``, sorted).

    Each step draws a sub-complex of ``q`` points with the rank probabilities ``weights`` and replaces its worst
    point ``alpha`` times by an offspring; returns the complex sorted by value again.
    """
    for _ in range(beta):
        chosen = np.sort(rng.choice(cf.size, size=q, replace=False, p=weights))
        sub_x, sub_f = cx[chosen], cf[chosen]
        for _ in range(alpha):
            sub_order = np.argsort(sub_f, kind="stable")
            sub_x, sub_f, chosen = sub_x[sub_order], sub_f[sub_order], chosen[sub_order]
            sub_x[-1], sub_f[-1] = _offspring(problem, sub_x, sub_f, cx, rng)
        cx[chosen], cf[chosen] = sub_x, sub_f
        complex_order = np.argsort(cf, kind="stable")
        cx, cf = cx[complex_order], cf[complex_order]
    return cx, cf


def _offspring(problem: CountedProblem, sub_x: np.ndarray, sub_f: np.ndarray, cx: np.ndarray,
               rng: np.random.Generator) -> tuple[np.ndarray, float]:
    """Replacement of the worst point of a sorted sub-complex and its value.

    The reflection through the centroid of the others; if it is not better, the halfway contraction; if neither
    is, a random point of the complex's enclosing box.  An infeasible trial point is not simulated: a reflection
    is replaced by a random feasible point of the box, a contraction counts as not better.
    """
    worst, worst_f = sub_x[-1], sub_f[-1]
    centroid = sub_x[:-1].mean(axis=0)
    lo, hi = cx.min(axis=0), cx.max(axis=0)
    new_x, new_f = centroid + (centroid - worst), math.inf
    if problem.feasible(new_x)[0]:
        new_f = _value(problem, new_x)
    else:
        z = _random_in_box(problem, lo, hi, rng)
        if z is not None:
            new_x, new_f = z, _value(problem, z)
    if not new_f < worst_f:
        new_x = 0.5 * (centroid + worst)
        new_f = _value(problem, new_x) if problem.feasible(new_x)[0] else math.inf
        if not new_f < worst_f:
            z = _random_in_box(problem, lo, hi, rng)
            new_x, new_f = (z, _value(problem, z)) if z is not None else (worst, worst_f)
    return new_x, new_f
