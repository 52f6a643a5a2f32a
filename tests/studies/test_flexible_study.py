"""The flexible slider-crank study recovers its reference design (the known optimum, f = 0) within 0.5 % in each of
l2, l3 and h with at most 600 simulations of the modal engine."""

from __future__ import annotations

import numpy as np

import mechopt


def test_the_sparse_pipeline_recovers_the_reference_design():
    study = mechopt.load_study("flexible-slider-crank")
    reference = study.design("reference")
    result = mechopt.minimize(study.problem, budget=600, seed=0, options={"search_points": 300_000})
    assert result.nfev <= 600 and result.success
    np.testing.assert_allclose(result.x, reference, rtol=5e-3)
    assert result.fun < 2e-3
