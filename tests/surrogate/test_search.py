"""Exhaustive search: known minima (free, on a constraint plane, on a non-convex constraint), grid, kernel."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.surrogate import LinePlan, SparseExponentialModel, exhaustive_search, grid_minimum, hull_grid

PAPER_DELTA = np.array([0.000, 0.920, 0.503])
PAPER_ORIGIN = np.array([31.000, 257.859, 72.705])
NODES7 = np.array([[0, 0], [10, 0], [5, 8], [-5, 8], [-10, 0], [-5, -8], [3, -4.0]])
P0, Q0, D0, LAM = 1.0, 2.0, 15.0, 0.12


def bowl(P, d):
    """(1 + 0.01 |P − P0|²)(e^{λ(d−d0)} + e^{−λ(d−d0)}): minimum 2 at (P0, Q0, D0); in the model class."""
    r2 = (P[:, 0] - P0) ** 2 + (P[:, 1] - Q0) ** 2
    return (1 + 0.01 * r2) * 2 * np.cosh(LAM * (d - D0))


@pytest.fixture(scope="module")
def fitted():
    E = LinePlan(PAPER_DELTA, PAPER_ORIGIN, np.zeros((1, 3))).normal_basis
    plan = LinePlan(PAPER_DELTA, PAPER_ORIGIN, NODES7 @ E)
    ks = np.arange(40)
    data = [(ks, bowl(*plan.coordinates(plan.points(i, ks)))) for i in range(7)]
    model = SparseExponentialModel().fit(plan, data)
    x_star = plan.from_coordinates([[P0, Q0]], [D0])[0]
    return model, plan, x_star


def test_finds_the_free_minimum(fitted):
    model, plan, x_star = fitted
    res = exhaustive_search(model, n_points=300_000)
    assert res.success and res.polish == "slsqp"
    # Grid point within one grid cell diagonal; polished point to 1e-5 (units of the coordinates).
    assert np.linalg.norm(res.x_grid - x_star) <= np.sqrt(3) * res.spacing
    assert np.linalg.norm(res.x - x_star) <= 1e-5
    assert res.fun == pytest.approx(2.0, abs=1e-9)
    assert 0.85 * 300_000 <= res.n_grid <= 1.15 * 300_000
    assert res.n_feasible == res.n_grid and res.n_evaluated >= res.n_grid
    assert set(res.timings) == {"grid", "feasibility", "evaluation", "polish", "total"}


def test_minimum_on_a_constraint_plane(fitted):
    model, plan, _ = fitted

    def feasible(X):  # p >= P0 + 3: the constrained minimum is at p = P0 + 3, q = Q0, d = D0
        return plan.normal_coordinates(X)[:, 0] >= P0 + 3.0

    res = exhaustive_search(model, feasible=feasible, n_points=200_000)
    (P, d) = plan.coordinates(res.x[None, :])
    assert feasible(res.x[None, :])[0]
    assert abs(P[0, 0] - (P0 + 3.0)) <= res.spacing
    assert abs(P[0, 1] - Q0) <= res.spacing and abs(d[0] - D0) * plan.spacing <= res.spacing
    assert res.fun == pytest.approx(2.0 * 1.09, abs=1e-3)  # (1 + 0.01·3²)·2, to grid resolution
    assert res.fun <= res.fun_grid


def test_minimum_on_a_non_convex_constraint(fitted):
    model, plan, x_star = fitted
    radius = 3.0

    def feasible(X):  # a hole around the free minimum: the answer lies on the sphere
        return np.linalg.norm(X - x_star, axis=1) >= radius

    # Reference: the model's minimum over a dense set of points of the sphere.
    rng = np.random.default_rng(0)
    u = rng.standard_normal((400_000, 3))
    sphere = x_star + radius * u / np.linalg.norm(u, axis=1)[:, None]
    reference = model.predict(sphere).min()
    res = exhaustive_search(model, feasible=feasible, n_points=200_000)
    assert feasible(res.x[None, :])[0] and res.polish == "local-sampling"
    assert abs(np.linalg.norm(res.x - x_star) - radius) <= res.spacing
    assert reference - 1e-6 <= res.fun <= reference + 1e-4


def test_without_polish_the_grid_point_is_returned(fitted):
    model, _, x_star = fitted
    res = exhaustive_search(model, n_points=50_000, polish=False)
    assert np.array_equal(res.x, res.x_grid) and res.polish == "none"
    assert np.linalg.norm(res.x - x_star) <= np.sqrt(3) * res.spacing


def test_nothing_feasible_is_reported(fitted):
    model, _, _ = fitted
    res = exhaustive_search(model, feasible=lambda X: np.zeros(len(X), bool), n_points=20_000)
    assert not res.success and np.all(np.isnan(res.x)) and "no feasible point" in res.message


def test_feasibility_is_called_in_chunks(fitted):
    model, _, _ = fitted
    sizes = []

    def feasible(X):
        sizes.append(len(X))
        return np.ones(len(X), bool)

    res = exhaustive_search(model, feasible=feasible, n_points=50_000, chunk=7_000, polish=False)
    assert max(sizes) <= 7_000 and sum(sizes) == res.n_grid
    assert len(sizes) == -(-res.n_grid // 7_000)


def test_grid_covers_exactly_the_hull(fitted):
    model, plan, _ = fitted
    grid = hull_grid(model, n_points=100_000)
    P, d = grid.coordinates(0, grid.n_points)
    X = plan.from_coordinates(P, d)
    assert model.contains(X).all()
    # Hull volume / cell volume predicts the number of points to within 10 %.
    assert abs(grid.n_points / (model.hull.volume / grid.spacing**3) - 1) <= 0.1
    box = hull_grid(model, n_points=100_000, hull=False)
    Pb, db = box.coordinates(0, box.n_points)
    assert not model.contains(plan.from_coordinates(Pb, db)).all()


def test_numba_kernel_matches_numpy(fitted):
    model, plan, _ = fitted
    grid = hull_grid(model, n_points=30_000)
    P, d = grid.coordinates(0, grid.n_points)
    values = model.predict_coordinates(P, d)
    mask = np.random.default_rng(1).random(grid.n_points) < 0.3
    fun, Pm, dm, n_eval = grid_minimum(model, grid, mask)
    j = np.flatnonzero(mask)[np.argmin(values[mask])]
    assert n_eval == mask.sum()
    assert fun == pytest.approx(values[j], rel=1e-12)
    assert np.allclose(Pm, P[j]) and dm == pytest.approx(d[j])


def test_two_dimensional_pipeline():
    # d = 2: four lines along y; (1 + 0.1 (x − 1.7)²) cosh(0.2 (y − 5)) is in the class (cubic blend in x).
    plan = LinePlan([0.0, 0.5], [0.0, 0.0], [[0, 0], [1, 0], [2.5, 0], [4, 0]])

    def f(X):
        return (1 + 0.1 * (X[:, 0] - 1.7) ** 2) * np.cosh(0.2 * (X[:, 1] - 5))

    ks = np.arange(30)
    model = SparseExponentialModel().fit(plan, [(ks, f(plan.points(i, ks))) for i in range(4)])
    res = exhaustive_search(model, n_points=20_000)
    assert np.allclose(res.x, [1.7, 5.0], atol=1e-6) and res.fun == pytest.approx(1.0, abs=1e-9)
