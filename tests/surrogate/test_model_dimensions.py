"""The blended model in d = 2 (a 1-D blend across lines in a plane) and d = 4 (a 3-D blend at Fekete nodes):
a function of the model's class is reproduced anywhere in the hull of the lines."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from mechopt.surrogate import LinePlan, SparseExponentialModel
from mechopt.surrogate.planner import fekete_points

LAMBDAS = np.array([-0.04, 0.015])


def _plan(direction: np.ndarray, nodes: np.ndarray) -> LinePlan:
    E = LinePlan(direction, np.zeros(direction.size), np.zeros((1, direction.size))).normal_basis
    return LinePlan(direction, np.zeros(direction.size), nodes @ E)


def _class_function(plan: LinePlan, coefficients):
    def f(X):
        P, d = plan.coordinates(X)
        return (coefficients(P) * np.exp(np.outer(d, LAMBDAS))).sum(axis=1)

    return f


def _check(plan: LinePlan, f, n_check: int = 400, seed: int = 0) -> float:
    ks = np.arange(0, 36)
    data = [(ks, f(plan.points(i, ks))) for i in range(plan.n_lines)]
    model = SparseExponentialModel(extrapolation="exponential").fit(plan, data)
    ends = model.plan.segment_ends().reshape(-1, plan.dim)
    w = np.random.default_rng(seed).dirichlet(np.full(len(ends), 0.5), n_check)
    X = w @ ends
    assert model.contains(X).all()
    exact = f(X)
    return float(np.max(np.abs(model.predict(X) - exact)) / np.max(np.abs(exact)))


def test_d2_a_function_of_the_class_is_reproduced_in_the_hull():
    # Four lines in the plane: the blend across them is a cubic in the normal coordinate p.
    direction = np.array([0.6, 0.25])
    nodes = np.array([[-3.0], [-1.0], [1.5], [3.0]])
    plan = _plan(direction, nodes)

    def coefficients(P):
        p = P[:, 0]
        return np.stack([1 + 0.1 * p - 0.02 * p**3, 0.4 + 0.05 * p * p], axis=1)

    assert _check(plan, _class_function(plan, coefficients)) < 1e-6


def test_d4_a_function_of_the_class_is_reproduced_in_the_hull():
    # Ten lines at approximate Fekete nodes of a 3-D normal space: the blend is a complete quadratic in (p, q, r).
    rng = np.random.default_rng(3)
    direction = np.array([0.3, 0.1, 0.7, 0.2])
    candidates = rng.uniform(-4, 4, size=(400, 3))
    nodes = candidates[fekete_points(candidates, 10)]
    plan = _plan(direction, nodes)

    def coefficients(P):
        p, q, r = P.T
        return np.stack([1 + 0.05 * p - 0.02 * q * r + 0.01 * r * r, 0.3 + 0.02 * q + 0.01 * p * q], axis=1)

    assert _check(plan, _class_function(plan, coefficients)) < 1e-6


@pytest.mark.parametrize("m", [1, 2, 3])
def test_fekete_points_are_unisolvent_for_the_complete_degree(m):
    # The Vandermonde matrix of the complete degree on the chosen nodes is square and well conditioned.
    from math import comb

    from numpy.polynomial.chebyshev import chebvander

    n = comb(2 + m, m)
    C = np.random.default_rng(1).uniform(-1, 1, size=(600, m))
    X = C[fekete_points(C, n)]
    tables = [chebvander(X[:, v], 2) for v in range(m)]
    V = np.column_stack([np.prod([tables[v][:, a] for v, a in enumerate(idx)], axis=0)
                         for idx in itertools.product(range(3), repeat=m) if sum(idx) <= 2])
    assert V.shape == (n, n) and np.linalg.cond(V) < 1e3
