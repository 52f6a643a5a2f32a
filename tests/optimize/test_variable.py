"""Variables of every kind (continuous, drawing grid, integer, catalogue) and the allowed designs of a problem."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.errors import InputError
from mechopt.optimize.auto.design_grid import DesignGrid
from mechopt.optimize.budget import CountedProblem
from mechopt.optimize.variable import Variable
from tests.optimize.mixed_problem import MixedBowl


def test_grid_variable_counts_snaps_and_lists_its_values():
    v = Variable("ab", 60.0, 130.0, "mm", step=0.1)
    assert (v.kind, v.count, v.discrete, v.describe_kind()) == ("grid", 701, True, "step 0.1 mm")
    assert v.snap(np.array([70.563, 59.0, 131.0, 70.549])).tolist() == [70.6, 60.0, 130.0, 70.5]
    assert v.allowed()[[0, 1, -1]].tolist() == [60.0, 60.1, 130.0]
    assert v.neighbours(70.563).tolist() == [70.5, 70.7]
    assert v.resolution == pytest.approx(0.1)


def test_integer_and_catalogue_variables():
    n = Variable("n", 3, 12, integer=True)
    assert (n.kind, n.count, n.snap(7.4), n.snap(7.6)) == ("integer", 10, 7.0, 8.0)
    d = Variable("d", unit="mm", values=[0.5, 0.63, 0.8, 1.0])
    assert (d.kind, d.lower, d.upper, d.count) == ("catalogue", 0.5, 1.0, 4)
    assert d.snap(np.array([0.56, 0.57, 0.95, 2.0])).tolist() == [0.5, 0.63, 1.0, 1.0]
    assert d.neighbours(0.63).tolist() == [0.5, 0.8] and d.neighbours(1.0).tolist() == [0.8]
    assert d.resolution == pytest.approx(0.13)


def test_a_continuous_variable_is_not_discrete():
    v = Variable("oa", 20.0, 40.0, "mm")
    assert (v.kind, v.count, v.discrete, v.resolution) == ("continuous", None, False, 0.0)
    assert v.snap(np.array([19.0, 33.3333])).tolist() == [20.0, 33.3333]
    with pytest.raises(InputError, match="continuous"):
        v.allowed()


@pytest.mark.parametrize(("kwargs", "message"), [
    (dict(lower=0.0, upper=1.0, step=0.3), r"step 0.3 does not divide \[0, 1\].*expected upper = 0.9 or 1.2"),
    (dict(values=(0.8, 0.5, 1.0)), "not increasing"),
    (dict(values=(0.5, 0.5, 1.0)), "repeat"),
    (dict(values=(0.5,)), "catalogue of 1 value"),
    (dict(lower=0.5, upper=4.0, integer=True), "integer=True with lower = 0.5"),
    (dict(lower=0.0, upper=1.0, step=0.1, integer=True), "step and integer given together"),
    (dict(lower=0.0, upper=1.0, step=-0.1), "positive step"),
    (dict(lower=0.4, values=(0.5, 1.0)), "lower = 0.4 but the catalogue's lower value is 0.5"),
])
def test_bad_variables_are_refused_in_one_line(kwargs, message):
    with pytest.raises(InputError, match=message) as info:
        Variable("v", **kwargs)
    assert "\n" not in str(info.value)


def test_problem_snaps_to_allowed_designs_and_counts_them():
    p = MixedBowl()
    assert p.discrete.tolist() == [False, True, True, True]
    assert p.design_count is None  # a continuous variable: infinitely many designs
    X = np.array([[0.123456, 1.26, 4.6, 0.7], [0.5, 1.3, 5.0, 0.63]])
    assert p.snap(X).tolist() == [[0.123456, 1.3, 5.0, 0.63], [0.5, 1.3, 5.0, 0.63]]
    assert p.on_grid(X).tolist() == [False, True]
    p.variables = p.variables[1:]
    assert p.design_count == 21 * 8 * 4


def test_design_grid_enumerates_and_moves_to_neighbours():
    grid = DesignGrid.of(MixedBowl())
    assert grid.count is None and not grid.all_discrete
    centre = np.array([0.4, 0.5, 0.5, 0.0])
    N = grid.neighbourhood(centre, radius=1)
    # The continuous variable kept; s in {0.9, 1.0, 1.1}, n in {4, 5, 6} (unit cube), d in its first two values.
    assert N.shape == (3 * 3 * 2, 4) and np.all(N[:, 0] == 0.4)
    assert np.allclose(np.unique(N[:, 1]) * 2.0, [0.9, 1.0, 1.1])
    small = DesignGrid([0, 0], [1, 3], [np.array([0.0, 0.5, 1.0]), np.array([0.0, 1.0, 2.0, 3.0])])
    assert small.count == 12 and small.enumerate().shape == (12, 2)
    assert small.enumerate(np.array([0.0, 0.0]), np.array([0.5, 0.4])).shape == (2 * 2, 2)


def test_counted_problem_simulates_a_rounded_design_once():
    p = MixedBowl()
    counted = CountedProblem(lambda x: p.evaluate(x)["f"], p.bounds, budget=5, snap=p.snap)
    a = counted.evaluate(np.array([0.3, 1.26, 4.4, 0.71]))
    b = counted.evaluate(np.array([0.3, 1.29, 3.6, 0.69]))  # rounds to the same design: free
    assert a == b and counted.nfev == 1 and counted.nproposals == 2
    assert counted.history[0].x.tolist() == [0.3, 1.3, 4.0, 0.63] and len(p.calls) == 1
