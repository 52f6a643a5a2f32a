"""``mechopt study --objective/--limit`` and a study file's ``objective`` and ``[limits]``: the ventilator's
trade-off run whole on the analytic engine, and bad input refused in one line."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mechopt.errors import StudyError
from mechopt.studies.catalogue import STUDIES_DIR, load_study

RUN = ["--engine", "analytic", "--workers", "1", "--no-progress"]


def mechopt(*args: str, timeout: float = 600):
    """Run ``mechopt ARGS`` in a subprocess, as a user types it."""
    return subprocess.run([sys.executable, "-m", "mechopt.cli.main", *args], capture_output=True, text=True,
                          env={**os.environ, "MPLBACKEND": "Agg"}, timeout=timeout)


def _study_file(tmp_path: Path, extra: str) -> Path:
    text = (STUDIES_DIR / "ventilator" / "study.toml").read_text()
    path = tmp_path / "study.toml"
    path.write_text(text.replace('method = "sparse"', f'method = "sparse"\n{extra}', 1))
    return path


def test_study_file_objective_and_limits_are_read(tmp_path):
    path = _study_file(tmp_path, 'objective = ["t_rms", "-toggle_margin_deg"]\n\n[limits]\nt_max = { upper = 6.0 }\n')
    problem = load_study(path, {"engine": "analytic"}).problem
    assert problem.objective_spec.names == ("t_rms", "toggle_margin_deg")
    assert problem.objective_spec.senses == (1.0, -1.0)
    assert problem.limit_spec.names == ("t_max",) and problem.limit_spec.upper[0] == 6.0


def test_study_file_limit_naming_no_output_is_refused(tmp_path):
    path = _study_file(tmp_path, '[limits]\nstress = [0.0, 1.0]\n')
    with pytest.raises(StudyError, match="limit on 'stress' names no output"):
        load_study(path, {"engine": "analytic"})


def test_ventilator_front_from_the_command_line(tmp_path):
    out = tmp_path / "run"
    proc = mechopt("study", "ventilator", *RUN, "--objective", "t_rms,-toggle_margin_deg", "--budget", "14",
                   "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    assert "expected hypervolume improvement on 2 objectives" in proc.stdout
    for name in ("report.md", "front.csv", "result.json", "figures/front.png", "figures/progress.png"):
        assert (out / name).is_file(), name
    rows = list(csv.reader((out / "front.csv").open()))
    assert rows[0][:3] == ["oa (mm)", "ab (mm)", "bc (mm)"] and "toggle_margin_deg (deg)" in rows[0]
    t_rms = np.array([float(r[rows[0].index("t_rms (N·m)")]) for r in rows[1:]])
    toggle = np.array([float(r[rows[0].index("toggle_margin_deg (deg)")]) for r in rows[1:]])
    # A front: sorted by T_RMS, and the toggle margin rises with it (each design trades one for the other).
    assert np.all(np.diff(t_rms) > 0) and np.all(np.diff(toggle) > 0) and np.all(toggle >= 15.0 - 1e-6)
    report = (out / "report.md").read_text()
    assert "paper_global_optimum" in report and "| |OA| (mm) |" in report


def test_one_objective_under_a_limit_from_the_command_line(tmp_path):
    proc = mechopt("study", "ventilator", *RUN, "--objective=-toggle_margin_deg", "--limit", "t_rms<=3.0",
                   "--budget", "14", "--out", str(tmp_path / "run"))
    assert proc.returncode == 0, proc.stderr
    assert "under limits t_rms <= 3" in proc.stdout
    line = next(x for x in proc.stdout.splitlines() if x.startswith("answer:"))
    assert float(line.split("t_rms = ")[1].split(",")[0]) <= 3.0


@pytest.mark.parametrize(("flags", "words"), [
    (["--limit", "t_rms<3"], "expected 'name<=value'"),
    (["--limit", "stress<=3"], "limit on 'stress' names no output"),
    (["--objective", "t_rms,t_max,toggle_margin_deg,t_rms,t_max"], "expected 1 to 4"),
    (["--limit", "4<=t_rms<=3"], "lower 4 > upper 3"),
])
def test_bad_objective_or_limit_is_one_line(tmp_path, flags, words):
    proc = mechopt("study", "ventilator", *RUN, *flags, "--budget", "14", "--out", str(tmp_path / "run"))
    err = proc.stderr.strip()
    assert proc.returncode != 0 and "Traceback" not in err and len(err.splitlines()) == 1, err
    assert words in err
    assert not (tmp_path / "run").exists()


def test_a_listed_test_problem_runs_as_a_study_and_compare_refuses_it_in_one_line(tmp_path):
    # `mechopt studies` lists the multi-objective test problems and says "run one with `mechopt study NAME`".
    proc = mechopt("study", "bnh", "--budget", "16", "--workers", "1", "--no-progress", "--out", str(tmp_path / "b"))
    assert proc.returncode == 0, proc.stderr
    rows = list(csv.DictReader((tmp_path / "b" / "front.csv").open()))
    assert rows and all(float(r["c1"]) <= 0.0 and float(r["c2"]) <= 0.0 for r in rows)
    proc = mechopt("compare", "--study", "bnh", "--budgets", "20", "--seeds", "1", "--out", str(tmp_path / "c"))
    assert proc.returncode != 0 and "has 2 objectives" in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "c").exists()
