"""Sobol indices: the Ishigami function's closed form, and brute force on the analytic four-bar."""

from __future__ import annotations

import numpy as np
import pytest

import mechopt
from mechopt.errors import InputError
from mechopt.optimize.analysis import sobol


def ishigami(X, a=7.0, b=0.1):
    return np.sin(X[:, 0]) + a * np.sin(X[:, 1]) ** 2 + b * X[:, 2] ** 4 * np.sin(X[:, 0])


def ishigami_indices(a=7.0, b=0.1):
    """Closed form (Ishigami & Homma 1990; Sobol' & Levitan 1999)."""
    v1 = 0.5 * (1 + b * np.pi**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = b**2 * np.pi**8 * (1 / 18 - 1 / 50)
    v = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


def test_ishigami_against_its_closed_form():
    first, total = sobol(ishigami, np.array([[-np.pi, np.pi]] * 3), n=2**14, seed=3)
    f, t = ishigami_indices()
    np.testing.assert_allclose(first, f, atol=0.02)
    np.testing.assert_allclose(total, t, atol=0.02)


def test_four_bar_indices_from_the_model_match_brute_force(tmp_path):
    problem = mechopt.load_study("ventilator", {"engine": "analytic"}).problem
    region = np.array([[33.0, 47.0], [72.0, 79.0], [262.0, 286.0]])  # inside the feasible region
    brute_first, brute_total = sobol(problem.evaluate_batch, region, n=2**11, seed=1)
    result = mechopt.sensitivity(problem, store=tmp_path / "s.sqlite", region=region, simulations=30)
    assert result.simulations == 30 and result.infeasible_share < 0.01
    np.testing.assert_allclose(result.first_order, brute_first, atol=0.03)
    np.testing.assert_allclose(result.total_order, brute_total, atol=0.03)


def test_a_region_outside_the_bounds_is_refused():
    problem = mechopt.load_study("ventilator", {"engine": "analytic"}).problem
    with pytest.raises(InputError, match="region"):
        mechopt.sensitivity(problem, region={"oa": (20.0, 40.0)})
    with pytest.raises(InputError, match="unknown variable 'xx'"):
        mechopt.sensitivity(problem, region={"xx": (20.0, 40.0)})
