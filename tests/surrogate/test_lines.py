"""LinePlan geometry: coordinates, feasible runs, hull, serialisation, bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mechopt.surrogate import LineHull, LinePlan, SurrogateError, normal_basis

PAPER_DELTA = np.array([0.000, 0.920, 0.503])  # Δ_u = 0 makes the paper's own (p, q) of Eq. 16 degenerate
PAPER_ORIGIN = np.array([31.000, 257.859, 72.705])


def paper_like_plan() -> LinePlan:
    rng = np.random.default_rng(0)
    offsets = rng.uniform(-10, 10, (7, 3))
    offsets[0] = 0.0
    return LinePlan(PAPER_DELTA, PAPER_ORIGIN, offsets)


@pytest.mark.parametrize("delta", [PAPER_DELTA, [1.0, 0.0, 0.0], [0.3, -0.2, 0.9], [0.0, 0.0, 2.0], [1.0, 1.0]])
def test_normal_basis_is_orthonormal_and_orthogonal(delta):
    delta = np.asarray(delta, dtype=float)
    E = normal_basis(delta)
    assert E.shape == (delta.size - 1, delta.size)
    assert np.allclose(E @ E.T, np.eye(delta.size - 1), atol=1e-14)
    assert np.allclose(E @ delta, 0.0, atol=1e-14)


def test_paper_delta_gives_u_as_first_normal_coordinate():
    E = normal_basis(PAPER_DELTA)
    assert np.allclose(E[0], [1.0, 0.0, 0.0])
    # (e1, e2, Δ̂) is right-handed.
    assert np.isclose(np.linalg.det(np.vstack([E, PAPER_DELTA / np.linalg.norm(PAPER_DELTA)])), 1.0)


def test_coordinates_follow_the_paper():
    plan = paper_like_plan()
    ks = np.arange(-3, 20)
    shifts = plan.line_shifts()
    for i in range(plan.n_lines):
        X = plan.points(i, ks)
        P, d = plan.coordinates(X)
        # d(kΔ + δ(i)) = k + d(δ(i)), and the normal coordinates are constant along a line (tolerance 1e-12).
        assert np.allclose(d, ks + shifts[i], atol=1e-12)
        assert np.allclose(P, plan.line_nodes()[i], atol=1e-12)
        assert np.allclose(plan.from_coordinates(P, d), X, atol=1e-12)
    assert np.allclose(plan.point(2, 5), PAPER_ORIGIN + 5 * PAPER_DELTA + plan.offsets[2])
    assert np.isclose(plan.spacing, np.linalg.norm(PAPER_DELTA))


def test_feasible_run_keeps_the_longest_contiguous_run():
    plan = LinePlan([0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [[0.0, 0.0, 0.0]])

    def feasible(X):
        z = X[:, 2]
        return ((z >= 2) & (z <= 4)) | ((z >= 7) & (z <= 15))

    run = plan.feasible_run(0, feasible, -5, 30)
    assert run.tolist() == list(range(7, 16))
    assert plan.feasible_run(0, lambda X: np.zeros(len(X), bool), 0, 10).size == 0


def test_hull_of_a_prism_contains_exactly_the_prism():
    # Four lines on the corners of [0, 2] x [0, 1] along z, sampled for z in [0, 3]: the hull is that box.
    corners = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]], dtype=float)
    plan = LinePlan([0.0, 0.0, 0.5], [0.0, 0.0, 0.0], corners, k_ranges=[[0, 6]] * 4)
    hull = plan.hull()
    assert isinstance(hull, LineHull) and np.isclose(hull.volume, 6.0)
    rng = np.random.default_rng(1)
    X = rng.uniform(-0.5, 3.5, (20_000, 3))
    inside = (X[:, 0] >= 0) & (X[:, 0] <= 2) & (X[:, 1] >= 0) & (X[:, 1] <= 1) & (X[:, 2] >= 0) & (X[:, 2] <= 3)
    assert np.array_equal(plan.hull_contains(X), inside)
    # Sample points on the boundary count as inside.
    assert plan.hull_contains(plan.points(1, np.arange(7))).all()


def test_flat_hull_is_reported():
    plan = LinePlan([0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [[0, 0, 0], [1, 0, 0], [2, 0, 0]], k_ranges=[[0, 3]] * 3)
    with pytest.raises(SurrogateError, match="flat") as info:
        plan.hull()
    assert "\n" not in str(info.value)


def test_round_trip_through_json():
    plan = paper_like_plan().with_k_ranges([[0, 10]] * 7)
    again = LinePlan.from_dict(json.loads(json.dumps(plan.to_dict())))
    for name in ("direction", "origin", "offsets", "k_ranges"):
        assert np.array_equal(getattr(again, name), getattr(plan, name))


@pytest.mark.parametrize(
    "kwargs,pattern",
    [
        ({"direction": [0.0, 0.0, 0.0]}, r"direction Δ must be non-zero, got \[0.0, 0.0, 0.0\]"),
        ({"direction": [0.0, np.nan, 1.0]}, r"direction Δ must be finite"),
        ({"origin": [0.0, 0.0]}, r"origin must have 3 components, got 2"),
        ({"offsets": [[0.0, 0.0]]}, r"offsets must have shape \(l, 3\)"),
        ({"offsets": [[0.0, np.nan, 0.0]]}, r"offsets δ\(i\) must be finite"),
        ({"k_ranges": [[0, 5], [3, 1]]}, r"k_lo <= k_hi"),
        ({"k_ranges": [[0, 5]]}, r"k_ranges must have shape \(2, 2\)"),
        ({"k_ranges": [[0, 5.5], [0, 3]]}, r"k_ranges must be integers"),
    ],
)
def test_bad_input_raises_one_line_error(kwargs, pattern):
    args = {"direction": [0.0, 1.0, 0.5], "origin": [0.0, 0.0, 0.0], "offsets": [[0, 0, 0], [1, 0, 0]]}
    args.update(kwargs)
    with pytest.raises(SurrogateError, match=pattern) as info:
        LinePlan(**args)
    assert "\n" not in str(info.value)


def test_plan_is_immutable():
    plan = paper_like_plan()
    with pytest.raises(ValueError):
        plan.offsets[0, 0] = 1.0
