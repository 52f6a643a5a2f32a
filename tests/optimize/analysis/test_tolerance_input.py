"""Bad tolerances, targets and designs are one-line InputErrors before any simulation."""

from __future__ import annotations

import numpy as np
import pytest

import mechopt
from mechopt.errors import InputError


class Counting(mechopt.DesignProblem):
    """A bowl under a linear margin that counts its simulations."""

    name = "counting-bowl"
    variables = (mechopt.Variable("a", 0.0, 2.0, "mm"), mechopt.Variable("b", 0.0, 2.0, "mm"))
    constraints = ("line",)
    outputs = ("f",)
    objective = "f"
    calls = 0

    def margins(self, X):
        return (1.5 - X[:, 0] - X[:, 1])[:, None]

    def evaluate(self, x):
        type(self).calls += 1
        return {"f": float((x[0] - 1.0) ** 2 + (x[1] - 1.0) ** 2)}


@pytest.mark.parametrize(("tolerances", "expected"), [
    ({"c": 0.1}, "unknown variable 'c'"),
    ({"a": -0.1}, "tolerance of a = -0.1"),
    ({"a": 3.0}, "expected at most its range 2"),
    ({"a": 0.0}, "every tolerance is zero"),
])
def test_bad_tolerances_are_refused_before_any_simulation(tolerances, expected):
    Counting.calls = 0
    with pytest.raises(InputError, match=expected) as info:
        mechopt.tolerance(Counting(), [0.5, 0.5], tolerances)
    assert "\n" not in str(info.value)
    with pytest.raises(InputError, match=expected):
        mechopt.minimize(Counting(), budget=10, tolerances=tolerances)
    assert Counting.calls == 0


@pytest.mark.parametrize("target", [0.0, 0.5, -0.1, 0.7, True, "0.01"])
def test_a_target_outside_0_to_half_is_refused(target):
    Counting.calls = 0
    with pytest.raises(InputError, match="max_violation"):
        mechopt.minimize(Counting(), budget=10, tolerances={"a": 0.1}, max_violation=target)
    assert Counting.calls == 0


def test_a_design_outside_the_box_is_refused():
    Counting.calls = 0
    with pytest.raises(InputError, match=r"a = 2.5 mm is outside its bounds \[0, 2\]"):
        mechopt.tolerance(Counting(), [2.5, 0.5], {"a": 0.1})
    with pytest.raises(InputError, match="design"):
        mechopt.tolerance(Counting(), [0.5, np.nan], {"a": 0.1})
    assert Counting.calls == 0


def test_distribution_and_statistic_are_checked():
    with pytest.raises(InputError, match="distribution = 'gauss'"):
        mechopt.Tolerances({"a": 0.1}, distribution="gauss")
    with pytest.raises(InputError, match="statistic = 1.5"):
        mechopt.Tolerances({"a": 0.1}, statistic=1.5)


def test_normal_scatter_has_a_third_of_the_tolerance_as_sigma():
    D = mechopt.Tolerances({"a": 0.3, "b": 0.6}, distribution="normal", samples=2**14).deviations(Counting())
    np.testing.assert_allclose(D.std(axis=0), [0.1, 0.2], rtol=0.01)
    U = mechopt.Tolerances({"a": 0.3}, samples=2**14).deviations(Counting())
    assert U[:, 0].min() >= -0.3 and U[:, 0].max() <= 0.3 and np.all(U[:, 1] == 0.0)
    np.testing.assert_allclose(U[:, 0].std(), 0.3 / np.sqrt(3.0), rtol=0.01)
