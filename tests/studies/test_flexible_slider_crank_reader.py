"""The flexible slider-crank design problem: known optimum, study file, settings, figures, bad input."""

import pickle
import tomllib
from pathlib import Path

import numpy as np
import pytest

from mechopt.errors import StudyError
from mechopt.sim.flexible_slider_crank.problem import FlexibleSliderCrankProblem
from mechopt.studies.kinds.flexible_slider_crank import problem_from_study
from mechopt.studies.study_file import PACKAGED_STUDIES, StudyFile

STUDY = PACKAGED_STUDIES / "flexible_slider_crank" / "study.toml"


def _study(config=None):
    cfg = tomllib.loads(STUDY.read_text()) if config is None else config
    return StudyFile(STUDY, cfg, "flexible_slider_crank")


@pytest.fixture(scope="module")
def problem():
    return problem_from_study(_study(), {})


def test_zero_at_the_reference_and_positive_away(problem):
    problem.check()
    ref = np.array([problem.target_mm[k] for k in ("l2", "l3", "h")])
    assert problem.evaluate(ref)["f"] == 0.0
    rng = np.random.default_rng(4)
    b = problem.bounds
    for x in rng.uniform(b[:, 0], b[:, 1], size=(4, 3)):
        out = problem.evaluate(x)
        assert out["f"] > 1e-3
        assert out["f"] == pytest.approx(0.4 * out["f_D"] + 0.3 * out["f_V"] + 0.3 * out["f_A"], rel=1e-12)
    # a small step in h alone changes only the deflection error
    near = problem.evaluate(ref + np.array([0.0, 0.0, 0.01]))
    assert near["f_V"] == 0.0 and near["f_A"] == 0.0 and near["f_D"] > 1e-4


def test_study_file_round_trip(problem):
    assert problem.engine == "modal"
    assert problem.bounds.tolist() == [[20.0, 80.0], [200.0, 500.0], [1.0, 2.0]]
    ex = problem_from_study(_study(), {"engine": "exudyn"})
    assert ex.engine == "exudyn" and ex.fingerprint() != problem.fingerprint()
    clone = pickle.loads(pickle.dumps(problem))
    assert clone.fingerprint() == problem.fingerprint()
    designs = tomllib.loads(STUDY.read_text())["designs"]
    assert problem.evaluate(np.array([designs["reference"][k] for k in ("l2", "l3", "h")]))["f"] == 0.0


def test_bad_study_values_are_one_line_errors():
    cfg = tomllib.loads(STUDY.read_text())
    cfg["mechanism"]["E_Pa"] = -1.0
    with pytest.raises(StudyError, match="mechanism.E_Pa"):
        problem_from_study(_study(cfg), {})
    cfg = tomllib.loads(STUDY.read_text())
    cfg["simulation"]["engine"] = "abaqus"
    with pytest.raises(StudyError, match="simulation.engine"):
        problem_from_study(_study(cfg), {})
    cfg = tomllib.loads(STUDY.read_text())
    cfg["simulation"]["n_modes"] = 40
    with pytest.raises(StudyError, match="n_modes"):
        problem_from_study(_study(cfg), {})


def test_figures_are_written(tmp_path: Path):
    problem = FlexibleSliderCrankProblem(base=None)
    made = problem.figures({"optimum": np.array([52.0, 360.0, 1.45])}, tmp_path)
    assert len(made) == 2
    for path in made.values():
        assert path.is_file() and path.stat().st_size > 10_000


def test_buckling_margin_separates_the_buckled_corner(problem):
    from mechopt.sim.flexible_slider_crank import FlexibleSliderCrank, simulate

    m = problem.margins(np.array([[50.0, 350.0, 1.53075], [76.1, 444.76, 1.003]]))[:, 0]
    assert m[0] > 0.5 and m[1] < 0.0
    # the geometrically exact engine confirms: beyond the Euler load the rod's deflection is tens of mm
    buckled = simulate(FlexibleSliderCrank.from_mm(76.1, 444.76, 1.003), "exudyn")
    assert np.max(np.abs(buckled.D)) > 0.01
