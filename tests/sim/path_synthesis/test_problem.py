"""The path-synthesis design problem: margins, evaluation, one-line errors, figures."""

import numpy as np
import pytest

from mechopt.errors import InfeasibleDesignError, InputError
from mechopt.sim.path_synthesis.feasibility import bar_ratio_margin, grashof_margin
from mechopt.sim.path_synthesis.points import read_points
from mechopt.sim.path_synthesis.problem import VARIABLES, PathSynthesisProblem
from mechopt.studies.study_file import PACKAGED_STUDIES

POINTS1 = read_points(PACKAGED_STUDIES / "path_synthesis_1" / "example1_points.csv")
BOUNDS1 = {"a1": (0.05, 5.0), "a2": (0.05, 15.0), **{k: (-15.0, 15.0) for k in ("a3", "a4", "a5")},
           "a6": (-np.pi, np.pi), "a7": (-20.0, 20.0), "a8": (-20.0, 20.0)}
TABLE2 = np.array([1.292, 3.277, 1.292, 3.875, 1.970, 3.090, 1.356, -0.583])


@pytest.fixture(scope="module")
def problem():
    return PathSynthesisProblem(POINTS1, BOUNDS1, max_ratio=3.0, name="example-1")


def test_declaration(problem):
    problem.check()
    assert problem.names == VARIABLES and problem.objective == "E" and problem.residuals == "residuals"
    assert problem.constraints[:2] == ("grashof_a5_up", "grashof_a5_down") and len(problem.constraints) == 14
    assert PathSynthesisProblem(POINTS1, BOUNDS1).constraints == ("grashof_a5_up", "grashof_a5_down")
    assert problem.settings()["points"][0] == [3.25, 1.701]


def test_margins_signs():
    X = np.array([TABLE2, [1.0, 2.0, 1.0, 1.0, 1.5, 0, 0, 0], [1.0, 3.0, 1.0, 3.5, -0.5, 0, 0, 0]])
    np.testing.assert_allclose(grashof_margin(X), [0.015, -0.5, 1.5], atol=1e-12)
    np.testing.assert_allclose(bar_ratio_margin(X), [0.001, 1.0, -0.5], atol=1e-12)
    np.testing.assert_allclose(bar_ratio_margin(X, 4.0), [1.293, 2.0, 0.5], atol=1e-12)
    # the problem's smooth pieces: their minima are the two margins, the same feasible set
    M = PathSynthesisProblem(POINTS1, BOUNDS1, max_ratio=3.0).constraint_margins(X)
    np.testing.assert_allclose(M[:, :2].min(axis=1), grashof_margin(X), atol=1e-12)
    np.testing.assert_allclose(M[:, 2:].min(axis=1), bar_ratio_margin(X), atol=1e-12)


def test_evaluate_table2(problem):
    out = problem.evaluate(TABLE2)
    assert out["E"] == pytest.approx(0.0073, rel=0.02) and out["branch"] == -1.0
    assert sum(r * r for r in out["residuals"]) == pytest.approx(out["E"], rel=1e-12)
    if hasattr(problem, "residual_vector"):  # DesignProblem's reader of the declared residuals
        assert np.sum(problem.residual_vector(out) ** 2) == pytest.approx(out["E"], rel=1e-12)
    assert len(out["residuals"]) == len(out["phi"]) == 16
    assert out["rms_distance"] == pytest.approx(np.sqrt(out["E"] / 16))
    assert all(np.isfinite(out[k]) for k in problem.outputs)
    assert problem.active_bounds(TABLE2) == ["bar_ratio margin 0.001"]


def test_a_crank_that_cannot_turn_fails_its_margin_and_raises_in_evaluate_only(problem):
    bad = TABLE2.copy()
    bad[4] = 2.5  # a1 + |a5| > a2
    assert problem.margins(bad[None])[0, 0] < 0  # margins never raise
    assert not problem.feasible(bad[None])[0]
    with pytest.raises(InfeasibleDesignError, match="crank cannot turn fully") as err:
        problem.evaluate(bad)
    assert "\n" not in str(err.value)
    ratio = TABLE2.copy()
    ratio[3] = 4.5
    with pytest.raises(InfeasibleDesignError, match="bar_ratio margin"):
        problem.evaluate(ratio)


def test_one_line_input_errors(tmp_path):
    with pytest.raises(InputError, match="lack a8"):
        PathSynthesisProblem(POINTS1, {k: v for k, v in BOUNDS1.items() if k != "a8"})
    with pytest.raises(InputError, match="a1 is a bar length"):
        PathSynthesisProblem(POINTS1, {**BOUNDS1, "a1": (-1.0, 5.0)})
    bad = tmp_path / "p.csv"
    bad.write_text("x,y\n1,2\n")
    with pytest.raises(InputError, match="header 'i,x,y'") as err:
        read_points(bad)
    assert "\n" not in str(err.value)
    bad.write_text("i,x,y\n1,2,a\n")
    with pytest.raises(InputError, match="three numbers"):
        read_points(bad)
    with pytest.raises(InputError, match="cannot read"):
        read_points(tmp_path / "missing.csv")


def test_figures(problem, tmp_path):
    opt = TABLE2 * np.array([1, 1.001, 1, 1, 1, 1, 1, 1])
    made = problem.figures({"paper_table2": TABLE2, "optimum": opt}, tmp_path)
    assert len(made) == 2
    for path in made.values():
        assert path.is_file() and path.stat().st_size > 10_000
    assert {p.suffix for p in made.values()} == {".png", ".gif"}
