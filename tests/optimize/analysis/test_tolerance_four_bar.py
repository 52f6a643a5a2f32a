"""Probabilities of violation and the objective's quantiles against brute-force Monte Carlo with the analytic
four-bar engine itself (10^4 designs drawn independently of the analysis' scatter)."""

from __future__ import annotations

import numpy as np
import pytest

import mechopt
from mechopt.sim.four_bar.feasibility import check_feasibility

#: The ventilator's optimum on the toggle margin, and a design 0.05 mm further in along |AB| and |BC|.
ON_MARGIN = np.array([30.0, 70.563, 254.585])
INSIDE = np.array([30.0, 70.52, 254.50])


@pytest.fixture(scope="module")
def problem():
    return mechopt.load_study("ventilator", {"engine": "analytic"}).problem


def _brute(problem, x, tol, distribution, n=10_000, seed=7):
    rng = np.random.default_rng(seed)
    D = rng.uniform(-tol, tol, (n, 3)) if distribution == "uniform" else rng.normal(0.0, tol / 3.0, (n, 3))
    X = x + D
    # The simulator's own verdict: the analytic engine reports a design feasible by this check.
    return ~check_feasibility(X, problem.mechanism).feasible, problem.evaluate_batch(X)


@pytest.mark.parametrize(("x", "distribution"), [(ON_MARGIN, "uniform"), (INSIDE, "normal")])
def test_violation_probability_matches_brute_force(problem, tmp_path, x, distribution):
    tol = mechopt.Tolerances(dict.fromkeys(problem.names, 0.1), distribution=distribution)
    result = mechopt.tolerance(problem, x, tol, store=tmp_path / "s.sqlite", simulations=12)
    bad, t_rms = _brute(problem, x, 0.1, distribution)
    p_brute = bad.mean()
    p = result.statistics.violation["any"]
    sigma = np.sqrt(p_brute * (1 - p_brute) / bad.size + result.statistics.standard_error["any"] ** 2)
    assert abs(p - p_brute) <= 4.0 * sigma + 1e-3, (p, p_brute)
    assert result.statistics.violation["toggle_deg"] == pytest.approx(p, abs=1e-12)
    if x is ON_MARGIN:  # on the margin about half the parts violate it
        assert 0.4 < p < 0.6
    # The objective's model against the simulator over the same scatter (its spread is about 2 % of its level).
    assert result.statistics.mean == pytest.approx(np.nanmean(t_rms), rel=1e-3)
    q_brute = np.nanquantile(t_rms, [0.05, 0.5, 0.95])
    np.testing.assert_allclose(list(result.statistics.quantiles.values()), q_brute, rtol=2e-3)
    assert result.simulations <= 12
    for c in result.confirmations:
        assert c["predicted"] == pytest.approx(c["simulated"], rel=2e-3)

