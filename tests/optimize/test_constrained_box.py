"""ConstrainedBox on its own: the cheap design space (box, margins, feasibility) without any counted objective."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.errors import InputError
from mechopt.optimize.budget import CountedProblem
from mechopt.optimize.constrained_box import BoxProblem, ConstrainedBox
from mechopt.optimize.problem import DesignProblem

BOX = [(0.0, 2.0), (-1.0, 1.0)]


def disk(x: np.ndarray) -> np.ndarray:
    """One margin: inside the disk of radius 1 around (1, 0)."""
    x = np.asarray(x, dtype=float)
    return np.atleast_1d(1.0 - (x[..., 0] - 1.0) ** 2 - x[..., 1] ** 2)


def disk_many(X: np.ndarray) -> np.ndarray:
    return disk(X).reshape(-1, 1)


@pytest.mark.parametrize(
    ("bounds", "message"),
    [([1.0, 2.0], r"shape \(d, 2\)"), ([(0.0, np.inf)], "finite with low < high"), ([(1.0, 1.0)], "low < high")],
)
def test_bad_bounds_are_input_errors(bounds, message):
    with pytest.raises(InputError, match=message):
        ConstrainedBox(bounds)


def test_feasibility_is_the_design_problems_one_design_or_a_batch():
    rng = np.random.default_rng(3)
    X = rng.uniform([-0.5, -1.5], [2.5, 1.5], size=(200, 2))
    for box in (ConstrainedBox(BOX, disk), ConstrainedBox(BOX, disk_many, vectorized_constraints=True)):
        assert isinstance(box.space, BoxProblem) and isinstance(box.space, DesignProblem)
        expected = np.all((X >= box.lower) & (X <= box.upper), axis=1) & (disk(X) >= 0.0)
        np.testing.assert_array_equal(box.feasible(X), expected)
        np.testing.assert_array_equal(box.space.feasible(X), expected)
        np.testing.assert_array_equal(np.concatenate([box.feasible(x) for x in X]), expected)
        assert box.space.constraints == ("g0",)
    assert 0 < expected.sum() < len(X)  # the sample has designs on both sides
    assert not ConstrainedBox(BOX, disk).feasible([[np.nan, 0.0], [1.0, 0.0]])[0]  # a failed step, not an error


def test_violation_sums_box_excess_and_negative_margins_and_nan_margins_count_as_violated():
    box = ConstrainedBox(BOX, disk)
    assert box.violation([1.0, 0.0]) == 0.0
    # 0.5 beyond the upper bound of x0; margin 1 - 1.5**2 = -1.25.
    assert box.violation([2.5, 0.0]) == pytest.approx(0.5 + 1.25)
    nan_box = ConstrainedBox(BOX, lambda x: np.array([np.nan]))
    assert nan_box.margins([1.0, 0.0]).tolist() == [-1.0]
    assert not nan_box.feasible([1.0, 0.0])[0]
    assert nan_box.has_constraints and not ConstrainedBox(BOX).has_constraints
    assert ConstrainedBox(BOX).margins([1.0, 0.0]).shape == (0,)


def test_unit_cube_faces_map_exactly_onto_the_box():
    box = ConstrainedBox([(0.1, 0.7), (-3.3, 1.9)])
    corners = box.from_unit(np.array([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]))
    assert box.feasible(corners).all()
    np.testing.assert_allclose(box.to_unit(corners), [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def test_boundary_point_is_feasible_and_on_the_constraint():
    box = ConstrainedBox(BOX, disk)
    p = box.boundary_point(np.array([1.0, 0.0]), np.array([1.0, 1.0]))
    assert box.feasible(p)[0]
    assert p[1] == pytest.approx(1.0, abs=1e-12)


def test_feasible_samples_are_feasible_and_seeded():
    box = ConstrainedBox(BOX, disk_many, vectorized_constraints=True)
    a = box.sample_feasible(40, np.random.default_rng(7))
    b = box.sample_feasible(40, np.random.default_rng(7))
    assert a.shape == (40, 2)
    assert box.feasible(a).all()
    np.testing.assert_array_equal(a, b)


def test_counted_problem_is_a_constrained_box_that_counts_only_the_objective():
    calls = []
    problem = CountedProblem(lambda x: calls.append(x) or float(x.sum()), BOX, 3, disk)
    assert isinstance(problem, ConstrainedBox)
    problem.feasible(np.zeros((10, 2)))
    problem.sample_feasible(5, np.random.default_rng(0))
    problem.boundary_point(np.array([1.0, 0.0]), np.array([3.0, 0.0]))
    assert problem.nfev == 0 and problem.nproposals == 0 and not calls
    with pytest.raises(InputError, match="budget must be a non-negative integer"):
        CountedProblem(sum, BOX, -1)
