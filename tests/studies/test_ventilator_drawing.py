"""The ventilator at drawing resolution: the answer lies on the 0.1 mm grid, meets every margin when simulated
again, and is within 0.5 % of the continuous optimum's T_RMS, which rounded to the grid is infeasible."""

from __future__ import annotations

import numpy as np
import pytest

import mechopt
from mechopt.studies.catalogue import load_study

#: The continuous ventilator study's optimum (mm), and its T_RMS on the analytic engine.
CONTINUOUS = np.array([30.0, 70.563, 254.585])


@pytest.fixture(scope="module")
def study():
    return load_study("ventilator-drawing", {"engine": "analytic"})


def test_rounding_the_continuous_optimum_is_not_the_answer(study):
    problem = study.problem
    assert all(v.kind == "grid" and v.step == 0.1 for v in problem.variables)
    assert problem.feasible(CONTINUOUS)[0]
    rounded = problem.snap(CONTINUOUS)
    assert rounded.tolist() == [30.0, 70.6, 254.6]
    toggle = problem.constraint_margins(rounded[None, :])[0][list(problem.constraints).index("toggle_deg")]
    assert toggle == pytest.approx(-0.1258, abs=1e-3)


def test_the_answer_is_on_the_grid_feasible_and_near_the_continuous_optimum(study):
    problem = study.problem
    res = mechopt.minimize(problem, budget=40, seed=0)
    x = np.asarray(res.x)
    assert problem.on_grid(x)[0] and np.allclose(x, np.round(x, 1), atol=1e-9)
    again = problem.evaluate(x)  # simulated again, outside the store
    assert again["t_rms"] == pytest.approx(res.fun, rel=1e-12)
    assert np.all(problem.constraint_margins(x[None, :]) >= 0.0) and again["toggle_margin_deg"] >= 15.0
    continuous = problem.evaluate(CONTINUOUS)["t_rms"]
    assert res.fun <= 1.005 * continuous
