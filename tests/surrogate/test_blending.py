"""Chebyshev blend: Lagrange property, polynomial reproduction, gradients, degenerate nodes."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.surrogate import ChebyshevBlend, SurrogateError


@pytest.mark.parametrize("l", [1, 2, 3, 4, 5, 6, 7, 10, 15])
def test_lagrange_functions_are_cardinal(l):
    rng = np.random.default_rng(l)
    nodes = rng.uniform(-40.0, 25.0, (l, 2))
    blend = ChebyshevBlend(nodes)
    assert np.allclose(blend.lagrange(nodes), np.eye(l), atol=1e-10)
    # The Lagrange functions form a partition of unity (constants are in every space).
    X = rng.uniform(-40.0, 25.0, (50, 2))
    assert np.allclose(blend.lagrange(X).sum(axis=1), 1.0, atol=1e-10)


def test_seven_nodes_give_complete_quadratics_plus_one_cubic():
    rng = np.random.default_rng(7)
    nodes = rng.uniform(0.0, 1.0, (7, 2))
    blend = ChebyshevBlend(nodes)
    degrees = blend.exponents.sum(axis=1)
    assert blend.degree == 3
    # The six monomials of degree <= 2 are columns of their own; the seventh function mixes degree-3 monomials.
    used = np.abs(blend.combinations) > 0
    assert all(used[degrees <= 2].sum(axis=1) == 1)
    assert used[degrees == 3].any(axis=0).sum() == 1


@pytest.mark.parametrize("l,degree", [(3, 1), (6, 2), (7, 2), (10, 3), (12, 3)])
def test_polynomials_of_complete_degree_are_reproduced(l, degree):
    rng = np.random.default_rng(100 + l)
    nodes = rng.uniform(-5.0, 5.0, (l, 2))
    coeffs = rng.standard_normal((degree + 1, degree + 1))

    def poly(P):
        out = np.zeros(len(P))
        for a in range(degree + 1):
            for b in range(degree + 1 - a):
                out += coeffs[a, b] * P[:, 0] ** a * P[:, 1] ** b
        return out

    blend = ChebyshevBlend(nodes)
    X = rng.uniform(-5.0, 5.0, (200, 2))
    assert np.max(np.abs(blend.lagrange(X) @ poly(nodes) - poly(X))) <= 1e-9 * np.max(np.abs(poly(X)))


def test_nodes_on_a_conic_still_admit_a_space():
    # Six nodes on a circle cannot separate the quadratics; the space takes a cubic instead.
    t = np.arange(6) * np.pi / 3
    blend = ChebyshevBlend(np.column_stack([np.cos(t), np.sin(t)]))
    assert blend.degree == 3 and blend.condition_number < 1e3


def test_gradient_matches_finite_differences():
    rng = np.random.default_rng(3)
    nodes = rng.uniform(-3.0, 3.0, (7, 2))
    blend = ChebyshevBlend(nodes)
    X = rng.uniform(-3.0, 3.0, (20, 2))
    h = 1e-6
    grads = blend.lagrange_gradient(X)
    for v in range(2):
        e = np.zeros(2)
        e[v] = h
        fd = (blend.lagrange(X + e) - blend.lagrange(X - e)) / (2 * h)
        assert np.max(np.abs(grads[:, :, v] - fd)) <= 1e-7


def test_one_dimensional_nodes():
    nodes = np.array([0.0, 1.0, 3.0, 4.5])
    blend = ChebyshevBlend(nodes)
    assert np.allclose(blend.lagrange(nodes), np.eye(4), atol=1e-12)
    x = np.linspace(0, 4.5, 9)
    assert np.allclose(blend.lagrange(x) @ nodes**3, x**3, atol=1e-10)


def test_round_trip_through_dict():
    rng = np.random.default_rng(5)
    blend = ChebyshevBlend(rng.uniform(0, 1, (7, 2)))
    again = ChebyshevBlend.from_dict(blend.to_dict())
    X = rng.uniform(0, 1, (30, 2))
    assert np.allclose(again.lagrange(X), blend.lagrange(X), atol=1e-13)


@pytest.mark.parametrize(
    "nodes,kwargs,pattern",
    [
        ([[0.0, 0.0], [1.0, 1.0], [0.0, 0.0]], {}, r"line nodes 0 and 2 coincide at \[0.0, 0.0\]"),
        ([[2.0, 2.0], [2.0, 2.0]], {}, r"coincide"),
        ([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]], {}, r"3 line nodes are collinear"),
        ([[0.0, 1.0], [1.0, 1.0], [2.0, 1.0], [5.0, 1.0], [7.0, 1.0]], {}, r"5 line nodes are collinear"),
        ([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0 + 1e-6]], {"cond_max": 1e3}, r"condition number"),
        ([[0.0, np.nan], [1.0, 0.0]], {}, r"finite"),
    ],
)
def test_degenerate_nodes_raise_one_line_error(nodes, kwargs, pattern):
    with pytest.raises(SurrogateError, match=pattern) as info:
        ChebyshevBlend(np.asarray(nodes), **kwargs)
    assert "\n" not in str(info.value)
