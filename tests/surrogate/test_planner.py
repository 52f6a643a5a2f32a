"""Line planner: coverage computed by hand, automatic plans, bad input."""

from __future__ import annotations

import time

import numpy as np
import pytest

from mechopt.surrogate import LinePlan, SurrogateError, coverage, plan_lines


def cell_centres(n):
    c = (np.arange(n) + 0.5) / n
    return np.stack(np.meshgrid(c, c, c, indexing="ij"), axis=-1).reshape(-1, 3)


def test_coverage_of_a_square_prism_is_its_volume_fraction():
    # Lines along z through the corners of [0.25, 0.75]^2 and its centre, sampled over z in [0, 1]: the hull is
    # the prism [0.25, 0.75]^2 x [0, 1], a quarter of the unit cube.  On the 40^3 cell centres (prism faces fall
    # between centres) the fraction is exactly 0.25.
    nodes = np.array([[0.25, 0.25], [0.75, 0.25], [0.75, 0.75], [0.25, 0.75], [0.5, 0.5]])
    offsets = np.column_stack([nodes, np.zeros(5)])
    plan = LinePlan([0.0, 0.0, 0.1], [0.0, 0.0, 0.0], offsets, k_ranges=[[0, 10]] * 5)
    assert coverage(plan, cell_centres(40)) == pytest.approx(0.25, abs=1e-12)
    # Shorter segments: z in [0.2, 0.7] halves it again (0.125), from k_ranges given explicitly.
    assert coverage(plan, cell_centres(40), k_ranges=[[2, 7]] * 5) == pytest.approx(0.125, abs=1e-12)


def test_coverage_of_a_triangular_prism_matches_its_area():
    # Triangle (0,0), (1,0), (0,1) in (x, y): area 1/2 of the unit square.  Monte-Carlo estimate within 4 sigma.
    offsets = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    plan = LinePlan([0.0, 0.0, 0.25], [0.0, 0.0, 0.0], offsets, k_ranges=[[0, 4]] * 3)
    pts = np.random.default_rng(0).random((40_000, 3))
    assert abs(coverage(plan, pts) - 0.5) <= 4 * np.sqrt(0.25 / 40_000)


def test_planner_on_a_box_region_reports_an_honest_coverage():
    # Feasible region: the box [0.2, 0.8] x [0.1, 0.6] x [0.3, 0.9] inside the unit-cube bounds.
    lo, hi = np.array([0.2, 0.1, 0.3]), np.array([0.8, 0.6, 0.9])

    def feasible(X):
        return np.all((X >= lo) & (X <= hi), axis=1)

    t = time.perf_counter()
    result = plan_lines([0, 0, 0], [1, 1, 1], feasible, n_lines=7, seed=1)
    assert time.perf_counter() - t < 5.0
    plan = result.plan
    assert plan.n_lines == 7 and np.all(plan.offsets[0] == 0) and np.all(plan.k_ranges[:, 0] == 0)
    # Every planned sample is feasible, and every line has a usable run.
    for i in range(7):
        ks = np.arange(plan.k_ranges[i, 0], plan.k_ranges[i, 1] + 1)
        assert ks.size >= 20 and feasible(plan.points(i, ks)).all()
    # The reported coverage agrees with an independent estimate on fresh points of the box (within 4 sigma + 0.005).
    fresh = lo + (hi - lo) * np.random.default_rng(99).random((30_000, 3))
    independent = coverage(plan, fresh)
    assert abs(result.coverage - independent) <= 4 * result.coverage_error + 0.005
    assert result.coverage > 0.75, result.message
    assert result.n_samples == int(np.sum(np.diff(plan.k_ranges, axis=1) + 1))


def test_planner_on_a_ball_and_in_two_dimensions():
    def ball(X):
        return np.sum((X - 0.5) ** 2, axis=1) < 0.16

    result = plan_lines([0, 0, 0], [1, 1, 1], ball, n_lines=7, samples_per_line=40)
    assert 0.5 < result.coverage <= 1.0
    disc = plan_lines([0, 0], [1, 1], lambda X: np.sum((X - 0.5) ** 2, axis=1) < 0.2, n_lines=4)
    assert disc.plan.dim == 2 and disc.coverage > 0.8


def test_explicit_spacing_is_used():
    result = plan_lines([0, 0, 0], [1, 1, 1], lambda X: np.ones(len(X), bool), spacing=0.05, n_probe=5000)
    assert result.plan.spacing == pytest.approx(0.05)


@pytest.mark.parametrize(
    "args,kwargs,pattern",
    [
        (([0, 0, 0], [1, 1, 1]), {"n_lines": 2}, r"n_lines must be >= d = 3 .*, got 2"),
        (([0, 0, 0], [1, 0, 1]), {}, r"upper > lower"),
        (([0, 0, 0, 0, 0], [1, 1, 1, 1, 1]), {}, r"length 2 to 4"),
        (([0, 0, 0], [1, 1, 1]), {"spacing": -1.0}, r"spacing must be a positive length, got -1.0"),
    ],
)
def test_bad_input_raises_one_line_error(args, kwargs, pattern):
    with pytest.raises(SurrogateError, match=pattern) as info:
        plan_lines(*args, lambda X: np.ones(len(X), bool), **kwargs)
    assert "\n" not in str(info.value)


def test_empty_feasible_region_is_reported():
    with pytest.raises(SurrogateError, match=r"only 0 of 2000 probe points are feasible"):
        plan_lines([0, 0, 0], [1, 1, 1], lambda X: np.zeros(len(X), bool), n_probe=2000)


def test_fekete_points_in_one_dimension_are_close_to_gauss_lobatto():
    # The Fekete points of degree-4 polynomials on [-1, 1] are the Gauss-Lobatto nodes 0, ±sqrt(3/7), ±1; the
    # greedy (approximate) ones chosen from a 0.01 grid land within 0.03 of them.
    from mechopt.surrogate.planner import fekete_points

    x = np.linspace(-1.0, 1.0, 201)[:, None]
    chosen = np.sort(x[fekete_points(x, 5)].ravel())
    exact = np.array([-1.0, -np.sqrt(3 / 7), 0.0, np.sqrt(3 / 7), 1.0])
    assert np.max(np.abs(chosen - exact)) < 0.03


def test_fekete_layout_keeps_the_blend_well_conditioned_where_the_boundary_layout_does_not():
    # 15 lines (a quartic blend) over a box region: the Lebesgue constant of the blend over the hull, max Σ|L_i|,
    # bounds how much line errors are amplified.  Fekete nodes keep it near that of the square's own Fekete points
    # (~5); nodes on the outline plus the centroid leave a quartic nearly undetermined inside (> 30).
    from mechopt.surrogate.blending import ChebyshevBlend

    lo, hi = np.array([0.2, 0.1, 0.3]), np.array([0.8, 0.6, 0.9])

    def feasible(X):
        return np.all((X >= lo) & (X <= hi), axis=1)

    pts = lo + (hi - lo) * np.random.default_rng(0).random((20_000, 3))
    lebesgue = {}
    for layout in ("fekete", "boundary"):
        result = plan_lines([0, 0, 0], [1, 1, 1], feasible, n_lines=15, samples_per_line=30, min_samples=10, seed=1,
                            layout=layout)
        inside = pts[result.plan.hull_contains(pts)]
        blend = ChebyshevBlend(result.plan.line_nodes())
        lebesgue[layout] = np.abs(blend.lagrange(result.plan.normal_coordinates(inside))).sum(axis=1).max()
        assert result.coverage > 0.8, result.message
    assert lebesgue["fekete"] < 8.0 and lebesgue["boundary"] > 30.0, lebesgue


def test_unknown_layout_is_a_one_line_error():
    with pytest.raises(SurrogateError, match=r"layout must be one of fekete, boundary, got 'grid'"):
        plan_lines([0, 0, 0], [1, 1, 1], lambda X: np.ones(len(X), bool), layout="grid")
