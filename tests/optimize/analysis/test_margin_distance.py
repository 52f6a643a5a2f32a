"""Distances to the active margins and the warnings a tolerance raises; the study file's [tolerances] table."""

from __future__ import annotations

import numpy as np
import pytest

import mechopt
from mechopt.errors import StudyError
from mechopt.optimize.analysis.margin_distance import margin_distances
from mechopt.studies.study_file import StudyFile
from mechopt.studies.tolerances_section import read_tolerances


class Bowl(mechopt.DesignProblem):
    name = "margin-bowl"
    variables = (mechopt.Variable("a", 0.0, 2.0, "mm"), mechopt.Variable("b", 0.0, 2.0, "mm"))
    constraints = ("line", "far")
    outputs = ("f",)
    objective = "f"

    def margins(self, X):
        return np.column_stack([1.5 - X[:, 0] - X[:, 1], 10.0 - X[:, 0]])

    def evaluate(self, x):
        return {"f": float(x[0] ** 2)}


def test_distance_to_a_linear_margin_and_the_default_tolerance_warning():
    r = margin_distances(Bowl(), [0.7, 0.75])
    assert set(r["active"]) == {"line"}
    line = r["active"]["line"]
    assert line["margin"] == pytest.approx(0.05)
    assert line["along"]["a"] == pytest.approx(0.05, rel=1e-6) and line["along"]["b"] == pytest.approx(0.05, rel=1e-6)
    assert line["nearest"] == pytest.approx(0.05 / np.sqrt(2.0), rel=1e-6)
    # ±0.1 mm uniform on both: P(δa + δb > 0.05) = (0.2 - 0.05)² / 0.08.
    assert line["violation"] == pytest.approx(0.15**2 / 0.08, abs=0.01)
    assert any("**warning**" in s and "28." in s for s in r["lines"])


def test_no_active_margin_far_inside():
    assert margin_distances(Bowl(), [0.2, 0.2])["lines"] == ["No margin is active at the optimum."]


def _file(tmp_path, table):
    return StudyFile(tmp_path / "study.toml", {"tolerances": table})


def test_the_tolerances_table_is_read_and_checked(tmp_path):
    read = read_tolerances(_file(tmp_path, {"a": 0.1, "distribution": "normal", "max_violation": 0.02}), Bowl())
    assert read.tolerances.values == {"a": 0.1} and read.tolerances.distribution == "normal"
    assert read.max_violation == 0.02
    assert read_tolerances(_file(tmp_path, {"a": 0.1}), Bowl()).max_violation is None
    for table, expected in (({"c": 0.1}, "unknown key tolerances.c"), ({"a": -1.0}, "must be >= 0"),
                            ({"a": 0.1, "max_violation": 0.6}, "max_violation = 0.6"),
                            ({"a": 5.0}, "at most its range"), ({"a": 0.1, "distribution": "x"}, "expected one of")):
        with pytest.raises(StudyError, match=expected):
            read_tolerances(_file(tmp_path, table), Bowl())
