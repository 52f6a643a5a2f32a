"""The flexible four-bar as a least-squares problem: its residual vector spells out Eq. 25 term by term."""

import numpy as np

from mechopt.sim.flexible_four_bar.problem import FlexibleFourBarProblem
from mechopt.sim.flexible_four_bar.response import TERMS


def test_residual_terms_sum_to_the_objective():
    problem = FlexibleFourBarProblem()
    assert problem.residuals == "residuals"
    n = problem.base.n_samples
    designs = ([285.0, 100.0, 250.0, 250.0, 1.53075, 1.53075], [280.0, 95.0, 260.0, 240.0, 1.4, 1.7],
               [250.0, 110.0, 230.0, 270.0, 1.8, 1.6], [290.0, 85.0, 280.0, 220.0, 1.2, 1.9])
    for x in designs:
        out = problem.evaluate(np.array(x))
        r = np.asarray(out["residuals"])
        assert r.shape == (8 * n,) and np.all(np.isfinite(r))
        # each path term holds its x then its y residuals (2 N), D3 and D4 N each
        parts = np.split(r, np.cumsum([2 * n, 2 * n, 2 * n, n]))
        terms = [float(np.sqrt(np.sum(part**2))) for part in parts]
        for term, key in zip(terms, TERMS, strict=True):
            assert np.isclose(term, out[key], rtol=1e-12, atol=0.0)
        if x == designs[0]:  # the target
            assert out["f"] == 0.0 and not np.any(r)
        else:
            assert abs(sum(terms) - out["f"]) <= 1e-12 * out["f"]
