"""DesignProblem.feasible with margins the caller already has: the same mask, and a clear error for a wrong shape."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.errors import InputError
from mechopt.studies.catalogue import load_study


def test_feasible_with_given_margins_is_feasible_without_them():
    problem = load_study("ventilator", {"engine": "analytic"}).problem
    rng = np.random.default_rng(3)
    b = problem.bounds
    # Designs inside the box and a little outside it: the bounds count whatever the margins say.
    X = b[:, 0] + (rng.random((400, 3)) * 1.2 - 0.1) * (b[:, 1] - b[:, 0])
    mask = problem.feasible(X)
    assert 0 < mask.sum() < len(X) and not problem.in_box(X).all()
    np.testing.assert_array_equal(problem.feasible(X, margins=problem.constraint_margins(X)), mask)
    with pytest.raises(InputError, match=r"margins of shape \(400, 2\) given for 400 designs; expected \(400, 5\)"):
        problem.feasible(X, margins=np.zeros((400, 2)))
