"""The robust optimum of a bowl under a linear margin, whose answer is known in closed form."""

from __future__ import annotations

import numpy as np
import pytest

import mechopt
from mechopt.optimize.analysis.robust import safe_level


class Bowl(mechopt.DesignProblem):
    """(a - 1)² + (b - 1)², a + b <= 1.5: the nominal optimum is (0.75, 0.75), on the margin."""

    name = "tolerance-bowl"
    variables = (mechopt.Variable("a", 0.0, 2.0, "mm"), mechopt.Variable("b", 0.0, 2.0, "mm"))
    constraints = ("line",)
    outputs = ("f",)
    objective = "f"

    def margins(self, X):
        return (1.5 - X[:, 0] - X[:, 1])[:, None]

    def evaluate(self, x):
        return {"f": float((x[0] - 1.0) ** 2 + (x[1] - 1.0) ** 2)}


def test_robust_optimum_keeps_the_margin_violated_at_most_the_target(tmp_path):
    tol = mechopt.Tolerances({"a": 0.1, "b": 0.1}, robust_simulations=20)
    res = mechopt.minimize(Bowl(), budget=30, seed=0, store=tmp_path / "s.sqlite", tolerances=tol,
                           max_violation=0.01)
    assert res.nominal_x == pytest.approx([0.75, 0.75], abs=5e-3)
    # δa + δb is triangular on [-0.2, 0.2]: P(δa + δb > s) = (0.2 - s)² / 0.08 at the safe level p.
    p = safe_level(0.01, tol.samples)
    s = 0.2 - np.sqrt(0.08 * p)
    assert res.x == pytest.approx([(1.5 - s) / 2] * 2, abs=4e-3)
    D = np.random.default_rng(3).uniform(-0.1, 0.1, (10_000, 2))
    brute = float(np.mean(res.x[0] + res.x[1] + D.sum(axis=1) > 1.5))
    assert brute <= 0.01 and res.robust.robust.violation["any"] <= 0.01
    assert res.robust.nominal.violation["any"] == pytest.approx(0.5, abs=0.03)
    assert res.robust.simulations <= 20
    assert res.fun == pytest.approx(Bowl().evaluate(res.x)["f"]) and res.robust.price > 0
