"""The flexible slider-crank study, a least-squares problem: every method recovers its reference design (the known
optimum, f = 0) within 0.01 % in each of l2, l3 and h, f <= 1e-8, with at most 600 simulations of the modal engine."""

from __future__ import annotations

import numpy as np
import pytest

import mechopt


def test_the_least_squares_plan_recovers_the_reference_to_a_hundredth_of_a_per_cent():
    # The issue asks f <= 1e-8 and l2, l3, h within 0.01 % with at most 600 simulations (SLSQP on the scalar
    # objective: f = 9e-5 after 921); Gauss-Newton on the residuals lands on the reference within 60 (measured).
    study = mechopt.load_study("flexible-slider-crank")
    result = mechopt.minimize(study.problem, budget=100, method="auto", seed=0)
    assert result.plan == "least-squares" and result.nfev <= 100
    assert result.fun <= 1e-8
    np.testing.assert_allclose(result.x, study.design("reference"), rtol=1e-4)


@pytest.mark.parametrize(("method", "budget"), [("sparse-global", 150), ("sparse", 600)])
def test_every_method_ends_on_gauss_newton_for_a_least_squares_problem(method, budget):
    # measured: sparse-global f = 0 from 140 simulations, sparse f = 0 from 546 (the reference design exactly)
    study = mechopt.load_study("flexible-slider-crank")
    options = {"search_points": 300_000} if method == "sparse" else None
    result = mechopt.minimize(study.problem, budget=budget, method=method, seed=0, options=options)
    assert result.nfev <= budget and result.fun <= 1e-8
    np.testing.assert_allclose(result.x, study.design("reference"), rtol=1e-4)
