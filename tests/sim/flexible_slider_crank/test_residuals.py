"""The flexible slider-crank as a least-squares problem: its residual vector spells out the objective term by term."""

import numpy as np

from mechopt.sim.flexible_slider_crank.problem import FlexibleSliderCrankProblem


def test_residual_terms_sum_to_the_objective():
    problem = FlexibleSliderCrankProblem()
    assert problem.residuals == "residuals"
    n = problem.base.n_samples
    for x in ([50.0, 350.0, 1.53075], [30.0, 250.0, 1.9], [70.0, 450.0, 1.6], [44.0, 300.0, 1.2]):
        out = problem.evaluate(np.array(x))
        r = np.asarray(out["residuals"])
        assert r.shape == (3 * n,) and np.all(np.isfinite(r))
        terms = [float(np.sqrt(np.sum(part**2))) for part in np.split(r, 3)]  # D, V, A in turn
        weights = problem.weights
        for w, term, key in zip(weights, terms, ("f_D", "f_V", "f_A"), strict=True):
            assert np.isclose(term, w * out[key], rtol=1e-12, atol=0.0)
        if x[0] == 50.0:  # the target
            assert out["f"] == 0.0 and not np.any(r)
        else:
            assert abs(sum(terms) - out["f"]) <= 1e-12 * out["f"]
