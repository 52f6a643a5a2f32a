"""``mechopt simulate`` end to end, and one-line errors for bad input."""

import json
import subprocess
import sys

import pytest

from mechopt.cli.main import EXIT_ERROR, EXIT_INFEASIBLE, main


def test_simulate_prints_feasibility_and_torques(capsys):
    assert main(["simulate", "--oa", "53", "--ab", "65", "--bc", "282", "--engine", "analytic"]) == 0
    out = capsys.readouterr().out
    assert "feasible" in out and "t_rms = 4.77" in out and "t_max = 8.06" in out


def test_simulate_a_problem_without_constraints_or_engine(capsys):
    # It printed "feasible (margins: )" and "engine : f = ...".
    assert main(["simulate", "--study", "hartmann3", "--x1", "0.1", "--x2", "0.5", "--x3", "0.8"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].endswith("feasible (the problem declares no constraints)")
    assert lines[1] == "simulated: f = -3.53704"  # Hartmann-3 at (0.1, 0.5, 0.8)


def test_simulate_json_and_plot(capsys, tmp_path):
    png = tmp_path / "orig.png"
    assert main(["simulate", "--oa", "53", "--ab", "65", "--bc", "282", "--json", "--plot", str(png)]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["engine"] == "pymunk" and payload["feasible"] is True
    assert payload["outputs"]["t_rms"] == pytest.approx(4.78, abs=0.01)
    assert payload["design"] == {"oa": 53.0, "ab": 65.0, "bc": 282.0}
    assert png.stat().st_size > 20_000


def test_infeasible_design_is_a_normal_answer(capsys):
    assert main(["simulate", "--oa", "30", "--ab", "120", "--bc", "260", "--json"]) == EXIT_INFEASIBLE
    payload = json.loads(capsys.readouterr().out)
    assert payload["feasible"] is False
    assert "not assemblable at ψ_start" in payload["message"]
    assert payload["margins"]["assembly_start_mm"] < 0


def _bad_toml(tmp_path, text):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--oa", "0", "--ab", "65", "--bc", "282"], "|OA| = 0 mm"),
        (["--oa", "53", "--ab", "-65", "--bc", "282"], "|AB| = -65 mm"),
        (["--oa", "53", "--ab", "65", "--bc", "nan"], "--bc = nan"),
        (["--oa", "53", "--ab", "65", "--bc", "282", "--study", "nosuch"], "unknown study 'nosuch'"),
    ],
)
def test_bad_input_is_one_line(capsys, args, expected):
    assert main(["simulate", *args]) == EXIT_ERROR
    err = capsys.readouterr().err.strip()
    assert expected in err and "\n" not in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("name = 'x'\n[mechanism\n", "malformed TOML"),
        ("name = 'x'\n", "missing key kind"),
        ("name = 'x'\nkind = 'five-bar'\n", "unknown mechanism kind 'five-bar'"),
        ("kind = 'four-bar'\n", "missing section [mechanism]"),
        ("kind = 'four-bar'\n[mechanism]\nground = 'explicit'\n[motion]\nstroke_time_s = 0.2\n",
         "missing key mechanism.pivot_c_mm"),
        ("kind = 'four-bar'\n[mechanism]\nground = 'explicit'\npivot_c_mm = [1, 2]\nj0_kgm2 = 1e-3\n"
         "i_r_kgm2 = 0.2\ncolour = 3\n[motion]\nstroke_time_s = 0.2\n", "unknown key mechanism.colour"),
        ("kind = 'four-bar'\n[mechanism]\nground = 'explicit'\npivot_c_mm = [1, 2]\nj0_kgm2 = 'heavy'\n"
         "i_r_kgm2 = 0.2\n[motion]\nstroke_time_s = 0.2\n", "key mechanism.j0_kgm2 = 'heavy'"),
    ],
)
def test_malformed_or_incomplete_toml(capsys, tmp_path, text, expected):
    study = _bad_toml(tmp_path, text)
    assert main(["simulate", "--oa", "53", "--ab", "65", "--bc", "282", "--study", study]) == EXIT_ERROR
    err = capsys.readouterr().err.strip()
    assert expected in err and "\n" not in err


def test_explicit_study_file(tmp_path, capsys):
    # A second study is just a TOML file: explicit pivot, inertias, stroke and a constant load.
    path = tmp_path / "bench.toml"
    path.write_text(
        "name = 'bench'\nkind = 'four-bar'\n[mechanism]\nground = 'explicit'\npivot_c_mm = [-235.0, 11.0]\n"
        "j0_kgm2 = 1.7e-3\ni_r_kgm2 = 0.2\n[motion]\nstroke_time_s = 0.2\npsi_start_deg = 16.4\n"
        "psi_end_deg = 6.2\n[load]\nrocker_Nm = 0.0\n[variables]\noa = [30, 60]\nab = [60, 130]\n"
        "bc = [250, 350]\n"
    )
    assert main(["simulate", "--oa", "53", "--ab", "65", "--bc", "282", "--study", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["outputs"]["t_rms"] > 0


def test_console_script_without_traceback():
    proc = subprocess.run(
        [sys.executable, "-m", "mechopt.cli.main", "simulate", "--oa", "-1", "--ab", "65", "--bc", "282"],
        capture_output=True, text=True, check=False,
    )
    assert proc.returncode == EXIT_ERROR
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr


def test_every_command_takes_the_study_as_its_first_word(capsys, tmp_path):
    # `mechopt study hartmann3` worked, `mechopt validate hartmann3` was "unrecognized arguments": each command now
    # takes the first word or --study, and one study named twice is an error unless both agree.
    assert main(["simulate", "hartmann3", "--x1", "0.1", "--x2", "0.5", "--x3", "0.8"]) == 0
    assert capsys.readouterr().out.splitlines()[1] == "simulated: f = -3.53704"
    assert main(["simulate", "--json", "hartmann3", "--x1", "0.1", "--x2", "0.5", "--x3", "0.8"]) == 0
    assert json.loads(capsys.readouterr().out)["outputs"]["f"] == pytest.approx(-3.53704, abs=1e-5)
    assert main(["study", "--study", "hartmann3", "--dry-run", "--out", str(tmp_path / "a")]) == 0
    assert "hartmann3" in capsys.readouterr().out
    out = str(tmp_path / "b")
    for command in (["study", "hartmann3", "--study", "branin", "--out", out],
                    ["truth", "hartmann3", "--study", "branin", "--out", out],
                    ["simulate", "hartmann3", "--study", "branin", "--x1", "0.1"]):
        assert main(command) == EXIT_ERROR
        err = capsys.readouterr().err
        assert "study named twice: 'hartmann3' and --study 'branin'" in err and err.count("\n") == 1
    assert not (tmp_path / "b").exists()


def test_an_empty_study_name_is_refused_not_read_as_the_default(capsys):
    # `mechopt compare ""` (an unset shell variable) ran every method on the ventilator.
    for command in (["compare", ""], ["study", "--study", "", "--dry-run"], ["compare", ","]):
        assert main(command) == EXIT_ERROR
        err = capsys.readouterr().err
        assert "names no study; expected a name such as ventilator" in err and err.count("\n") == 1
