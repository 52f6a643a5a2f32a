"""Report defects of issue 25: errors against a range (never a percentage of a value near 0), one period, one slice
per value, and units on the validation figure's axes."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.optimize.sparse.validate import Validation
from mechopt.report.plots import _slice_values, plot_validation
from mechopt.report.study_report import _validation_paragraph
from mechopt.studies.catalogue import load_study


def test_relative_error_is_a_share_of_the_range_never_of_a_value_near_zero():
    v = Validation(lines=[], rmse=0.0192, rmse_low=0.0192, max_error=0.06194, f_min=-0.05777, n_points=12,
                   spread=0.2795)
    text = v.relative_text("N·m")
    assert text == "6.87 % of the held-out values' range 0.2795 N·m"
    assert "best simulated" not in text


def test_validation_paragraph_ends_with_one_period_and_has_units():
    v = {"n_points": 12, "n_lines": 2, "rmse": 0.0192, "relative": "6.87 % of the range", "rmse_low": 0.01,
         "max_error": 0.06194, "unit": "N·m"}
    text = _validation_paragraph(v, "t_rms", {})[-1]
    assert text.endswith("largest error 0.06194 N·m.") and ".." not in text
    with_paper = _validation_paragraph(v, "t_rms", {"validation_rmse": 0.0281})[-1]
    assert with_paper.endswith("The paper: RMSE 0.0281.") and ".." not in with_paper


@pytest.mark.parametrize("oa", [30.0, 30.0 + 3e-10, 30.0 - 3e-10, 60.0 - 1e-12])
def test_an_optimum_on_a_bound_is_that_bound_s_slice_not_a_second_one(oa):
    problem = load_study("ventilator", {"engine": "analytic"}).problem
    marks = {"original": np.array([53.0, 65.0, 282.0]), "optimum": np.array([oa, 70.457, 254.383])}
    values = _slice_values(problem, marks, 4)
    assert len(values) == 4 and np.all(np.diff(values) > 1e-3), values  # no slice twice
    assert any(abs(v - oa) < 1e-6 for v in values) and any(abs(v - 53.0) < 1e-9 for v in values)
    assert all(30.0 <= v <= 60.0 for v in values)


def test_validation_figure_axes_carry_the_unit(tmp_path, monkeypatch):
    import matplotlib.axes

    labels: list[str] = []
    original = matplotlib.axes.Axes.set_ylabel
    monkeypatch.setattr(matplotlib.axes.Axes, "set_ylabel",
                        lambda self, text, *a, **k: labels.append(text) or original(self, text, *a, **k))
    lines = [{"designs": [[0, 0, 0]] * 3, "simulated": [1.0, 2.0, 3.0], "predicted": [1.1, 2.0, 2.9]}]
    path = plot_validation(lines, tmp_path / "v.png", label="t_rms (N·m)", unit="N·m")
    assert path.is_file() and labels == ["t_rms (N·m)", "model − simulation (N·m)"]
