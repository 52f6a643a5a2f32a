"""Paper 001's offset crank-slider study: its case-study numbers, its equations, the true optimum, bad studies."""

import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize

from mechopt.errors import InfeasibleDesignError, StudyError
from mechopt.studies.kinds.offset_crank_slider import paper_eq9_10, problem_from_study, regression_design
from mechopt.studies.study_file import PACKAGED_STUDIES, StudyFile

STUDY = PACKAGED_STUDIES / "offset_crank_slider" / "study.toml"


def _study(tmp_path=None, **changes):
    config = tomllib.loads(STUDY.read_text())
    for section, values in changes.items():
        config.setdefault(section, {}).update(values)
    return StudyFile(STUDY if tmp_path is None else Path(tmp_path) / "study.toml", config, "offset_crank_slider")


@pytest.fixture(scope="module")
def problem():
    return problem_from_study(_study(), {})


def test_regression_design_is_the_paper_models_at_its_targets():
    hn, r3n = regression_design(2.12, 1.15)  # Eqs. 22–23 as printed, at the paper's Sopt, TRopt
    assert hn == pytest.approx(0.9649, abs=5e-5) and r3n == pytest.approx(3.1164, abs=5e-5)


def test_paper_case_study_numbers(problem):
    reg = problem.evaluate(np.array([0.9649, 3.1164]))
    assert reg["stroke_n"] == pytest.approx(2.12, abs=5e-3)  # paper: Sopt = 2.12
    assert reg["ta_min_deg"] == pytest.approx(89.355, abs=5e-4)
    assert reg["ta_max_deg"] == pytest.approx(129.087, abs=5e-4)
    # The paper's TRopt = 1.15 is not this design's time ratio (1.163): see README.
    assert reg["time_ratio"] == pytest.approx(1.1630, abs=5e-4)
    conv = problem.evaluate(np.array([1.385, 2.625]))
    assert conv["stroke_mm"] == pytest.approx(250.0, abs=0.01)
    assert conv["time_ratio"] == pytest.approx(1.5, abs=1e-4)
    assert conv["ta_min_deg"] == pytest.approx(98.434, abs=5e-4)
    assert conv["ta_max_deg"] == pytest.approx(155.309, abs=5e-4)
    # Feasibility as the paper says: the regression design keeps TA in range, the conventional one does not.
    assert problem.feasible(np.array([[0.9649, 3.1164]]))[0]
    assert not problem.feasible(np.array([[1.385, 2.625]]))[0]


def test_printed_eqs_9_10_do_not_reproduce_the_reported_ranges():
    ta_min, ta_max = paper_eq9_10(0.9649, 3.1164)
    assert ta_min == pytest.approx(89.355, abs=2e-3)  # coincides near hn = 1 only
    assert abs(ta_max - 129.087) > 4.0
    ta_min, ta_max = paper_eq9_10(1.385, 2.625)
    assert abs(ta_min - 98.434) > 0.2 and abs(ta_max - 155.309) > 10.0


def test_vectorised_quantities_match_evaluate(problem):
    rng = np.random.default_rng(0)
    X = np.column_stack([rng.uniform(0.1, 1.5, 50), rng.uniform(3.0, 10.0, 50)])
    q = problem.quantities(X)
    for i in range(0, 50, 7):
        out = problem.evaluate(X[i])
        for key in ("objective", "stroke_n", "time_ratio", "ta_min_deg", "ta_max_deg"):
            assert out[key] == pytest.approx(q[key][i], rel=1e-12)


def test_true_optimum_by_grid_and_polish(problem):
    g = np.meshgrid(*(np.linspace(lo, hi, 301) for lo, hi in problem.bounds), indexing="ij")
    X = np.column_stack([v.ravel() for v in g])
    f = np.where(problem.feasible(X), problem.quantities(X)["objective"], np.inf)
    x0 = X[np.argmin(f)]
    cons = [{"type": "ineq", "fun": lambda x, j=j: problem.margins(x[None])[0, j]} for j in range(6)]
    res = minimize(lambda x: problem.evaluate(x)["objective"], x0, method="SLSQP", bounds=problem.bounds,
                   constraints=cons, options={"ftol": 1e-14, "maxiter": 300})
    # Closed form: TA_min = 90° (hn = 1) and TA_max = 135° (r3n = 2/sin 45° = 2√2) both active.
    np.testing.assert_allclose(res.x, [1.0, 2 * np.sqrt(2)], atol=1e-6)
    assert res.fun == pytest.approx(0.189421, abs=1e-6)
    out = problem.evaluate(np.array([1.0, 2 * np.sqrt(2)]))
    assert out["time_ratio"] == pytest.approx(1.2224, abs=1e-4)  # the paper's largest TRopt: 1.224
    assert res.fun < problem.evaluate(np.array([0.9649, 3.1164]))["objective"]


def test_evaluate_is_fast_and_refuses_a_crank_that_cannot_turn(problem):
    import time

    x = np.array([0.9649, 3.1164])
    start = time.perf_counter()
    for _ in range(200):
        problem.evaluate(x)
    assert (time.perf_counter() - start) / 200 < 2e-4
    with pytest.raises(InfeasibleDesignError, match="cannot turn fully"):
        problem.evaluate(np.array([2.0, 2.5]))


def test_bad_studies_are_one_line_errors():
    with pytest.raises(StudyError, match="no feasible design"):
        problem_from_study(_study(variables={"hn": [1.5, 3.0]}), {})  # TA_min <= 90° needs hn <= 1
    with pytest.raises(StudyError, match="unreachable"):
        problem_from_study(_study(targets={"stroke_mm": 150.0}), {})
    with pytest.raises(StudyError, match="unreachable"):
        problem_from_study(_study(targets={"time_ratio": 0.8}), {})
    with pytest.raises(StudyError, match="lower < upper"):
        problem_from_study(_study(variables={"hn": [2.0, 1.0]}), {})
    with pytest.raises(StudyError, match="unknown key"):
        problem_from_study(_study(targets={"strok_mm": 1.0}), {})
    with pytest.raises(StudyError, match="engine"):
        problem_from_study(_study(), {"engine": "exudyn"})


def test_figures(problem, tmp_path):
    figs = problem.figures({"paper_regression": np.array([0.9649, 3.1164])}, tmp_path)
    assert len(figs) == 2
    for path in figs.values():
        assert path.is_file() and path.stat().st_size > 1000
