"""``mechopt tolerance`` end to end on the analytic four-bar, and one-line errors for bad input."""

from __future__ import annotations

import json

import pytest

from mechopt.cli.main import EXIT_ERROR, main

DESIGN = "oa=30,ab=70.563,bc=254.585"


def test_tolerance_prints_the_violation_and_writes_json_and_figures(capsys, tmp_path):
    out = tmp_path / "out"
    assert main(["tolerance", "ventilator", "--engine", "analytic", "--design", DESIGN, "--tol", "0.1",
                 "--store", str(tmp_path / "s.sqlite"), "--simulations", "10", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "toggle_deg" in text and "new simulations: 10" in text
    payload = json.loads((out / "tolerance.json").read_text())["tolerance"]
    assert 0.4 < payload["violation"]["toggle_deg"] < 0.6
    assert payload["tolerances"] == {"oa": 0.1, "ab": 0.1, "bc": 0.1} and payload["simulations"] == 10
    assert (out / "tolerance.png").stat().st_size > 20_000


@pytest.mark.parametrize(("args", "expected"), [
    (["--tol", "-0.1"], "tolerance of oa = -0.1"),
    (["--tol-of", "xx=0.1"], "unknown variable 'xx'"),
    (["--tol", "200"], "expected at most its range"),
    (["--tol", "0.1", "--design", "oa=20,ab=70,bc=254"], "oa = 20 mm is outside its bounds"),
    (["--tol", "0.1", "--design", "oa=30,ab=70"], "bc missing"),
    ([], "no tolerance given"),
])
def test_bad_input_is_one_line_before_any_simulation(capsys, tmp_path, args, expected):
    argv = ["tolerance", "ventilator", "--engine", "analytic", "--design", DESIGN, "--store",
            str(tmp_path / "s.sqlite"), *args]
    if "--design" in args:
        argv[4:6] = []
    assert main(argv) == EXIT_ERROR
    err = capsys.readouterr().err.strip()
    assert expected in err and "\n" not in err
    assert not (tmp_path / "s.sqlite").exists() or "s.sqlite" not in err
