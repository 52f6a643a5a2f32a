"""Study files with grid, integer and catalogue variables: read into the problem's variables, a bad entry refused in
one line naming the file and the key, and a run whose plan, report and result.json say which variables are
discrete and how many designs the space holds."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mechopt.cli.main import main
from mechopt.errors import StudyError
from mechopt.studies.catalogue import load_study

MODULE = '''def simulate(d):
    return {"f": (d["w"] - 1.27) ** 2 + 0.1 * (d["n"] - 4.4) ** 2 + (d["d"] - 0.7) ** 2 + (d["x"] - 0.3) ** 2}
'''


def _study(folder, variables: str, extra: str = "") -> object:
    (folder / "mixed_sim.py").write_text(MODULE)
    toml = folder / "study.toml"
    toml.write_text(f'name = "mixed"\nkind = "external"\n[variables]\n{variables}\n[simulator]\n'
                    f'callable = "mixed_sim:simulate"\noutputs = ["f"]\n{extra}')
    return toml


MIXED = ('w = { bounds = [0, 2], step = 0.1, unit = "mm" }\nn = { bounds = [3, 6], integer = true }\n'
         'd = { values = [0.5, 0.63, 0.8, 1.0], unit = "mm" }\nx = [0.0, 1.0]')


def test_a_study_file_declares_every_kind_of_variable(tmp_path):
    problem = load_study(_study(tmp_path, MIXED)).problem
    w, n, d, x = problem.variables
    assert (w.kind, w.step, w.count, w.unit) == ("grid", 0.1, 21, "mm")
    assert (n.kind, n.lower, n.upper, n.count) == ("integer", 3.0, 6.0, 4)
    assert (d.kind, d.values, d.lower, d.upper) == ("catalogue", (0.5, 0.63, 0.8, 1.0), 0.5, 1.0)
    assert x.kind == "continuous" and problem.design_count is None


@pytest.mark.parametrize(("entry", "message"), [
    ("w = { bounds = [0, 2], stepp = 0.1 }", r"unknown key variables.w.stepp; expected one of \['bounds'"),
    ("w = { bounds = [0, 2], step = 0.3 }", r"key variables.w: variable w: step 0.3 does not divide \[0, 2\]"),
    ("w = { values = [0.8, 0.5] }", "not increasing"),
    ("w = { values = [0.5] }", "catalogue of 1 value"),
    ("w = { bounds = [0.5, 4], integer = true }", "integer=True with lower = 0.5"),
    ("w = { bounds = [0, 4], integer = 1 }", "integer = 1 must be true or false"),
    ("w = { step = 0.1 }", "has no bounds"),
    ("w = { bounds = [0, 2], lower = 0 }", "gives bounds and lower/upper"),
])
def test_a_bad_variable_entry_is_refused_in_one_line(tmp_path, entry, message):
    with pytest.raises(StudyError, match=message) as info:
        load_study(_study(tmp_path, entry))
    assert "\n" not in str(info.value) and "study.toml" in str(info.value)


def test_a_finite_space_is_counted_in_the_plan_and_the_report(tmp_path, capsys):
    variables = ('w = { bounds = [0, 2], step = 0.1 }\nn = { bounds = [3, 6], integer = true }\n'
                 'd = { values = [0.5, 0.63, 0.8, 1.0] }')
    toml = _study(tmp_path, variables)
    (tmp_path / "mixed_sim.py").write_text(MODULE.replace(' + (d["x"] - 0.3) ** 2', ""))
    out = tmp_path / "out"
    code = main(["study", str(toml), "--method", "auto", "--budget", "30", "--workers", "1", "--no-progress",
                 "--out", str(out)])
    printed = capsys.readouterr().out
    assert code == 0, printed
    assert "discrete variables: w step 0.1, n integer, d catalogue of 4; 336 distinct designs" in printed
    result = json.loads((out / "result.json").read_text())
    assert result["allowed_designs"]["design_count"] == 21 * 4 * 4
    assert [v["kind"] for v in result["problem"]["variables"]] == ["grid", "integer", "catalogue"]
    design = result["optimum"]["design"]
    assert load_study(toml).problem.on_grid(np.array([design[k] for k in "wnd"]))[0]
    # The best allowed design (brute force over the 336): w = 1.3, n = 4, d = 0.63 or 0.8 (equal: 0.07² each).
    assert (design["w"], design["n"]) == (1.3, 4.0) and design["d"] in (0.63, 0.8)
    assert "The space holds 336 distinct designs" in (out / "report.md").read_text()
