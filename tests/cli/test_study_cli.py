"""Every CLI command end to end on a small configuration, and figures that are real images."""

import json
import re

import numpy as np
import pytest

from mechopt.cli.main import EXIT_ERROR, main

SMALL = ["--engine", "analytic", "--workers", "1", "--no-progress", "--samples-per-line", "24",
         "--search-points", "200000", "--points-per-line", "8"]
#: The ventilator's true optimum, T_RMS in N·m (brute force: see test_ground_truth.py).
T_TRUE = 1.7582


@pytest.fixture(scope="module")
def study_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    assert main(["study", "ventilator", "--out", str(out), "--lines", "6", *SMALL]) == 0
    return out


def _is_png(path, min_bytes=10_000):
    data = path.read_bytes()
    return data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > min_bytes


def test_study_writes_result_report_and_figures(study_dir):
    result = json.loads((study_dir / "result.json").read_text())
    assert result["simulations"]["model_lines"] < 618
    assert result["validation"]["n_points"] >= 40
    # The global model (21 lines at Fekete nodes, blended T_RMS²) on held-out lines: RMSE within 1 % of T_min.
    assert result["validation"]["rmse"] <= 0.01 * T_TRUE, result["validation"]
    opt = result["optimum"]
    original = next(d for d in result["designs"] if d["name"] == "original")
    assert opt["objective"] < 0.5 * original["outputs"]["t_rms"]  # far better than the original
    # Within 0.5 % of the brute-force ground truth even in this small configuration.
    assert opt["objective"] < 1.005 * T_TRUE
    assert result["ground_truth"] is None  # opt-in: not part of every study run
    sims = result["simulations"]
    assert sims["new"] + sims["reused"] == sims["distinct_designs"] and sims["executor"]
    report = (study_dir / "report.md").read_text()
    assert "| original |" in report and "paper_global_optimum" in report and "reused from the store" in report
    assert "| t_rms savings |" in report and "| 63." in report  # against the original design
    # The trust report: its measures and its verdict, in result.json and in the report.
    trust = result["trust"]
    assert trust["verdict"] and trust["verdict"] in report
    assert trust["source"] in {s["name"] for s in result["stages"]}
    assert 0 <= trust["claim_error"] < 1 and trust["resolved"] == (max(
        v for v in (trust["lolo_median"], trust["claim_error"], trust["heldout_error"]) if v is not None) <= 0.05)
    for rel in result["figures"].values():
        path = study_dir / rel
        assert path.is_file() and path.stat().st_size > 10_000, rel
        if rel.endswith(".png"):
            assert _is_png(path)
        elif rel.endswith(".gif"):
            assert path.read_bytes()[:6] in (b"GIF87a", b"GIF89a")
    assert (study_dir / "samples.sqlite").is_file() and (study_dir / "model.json").is_file()
    # The progress figure's data: the objective of every simulation the method asked for, in order; its best is
    # the optimum reported.
    history = np.array(result["history"], dtype=float)
    assert history.size == result["simulations"]["optimisation"]
    assert np.nanmin(history) == pytest.approx(opt["objective"], rel=1e-12)
    assert "figures/progress.png" in result["figures"].values()


def test_a_study_without_constraints_or_lines(tmp_path):
    # auto on a test function: no line-model stages in the report and no one-colour feasible-region figure; the
    # progress figure and the run's message instead.
    assert main(["study", "hartmann3", "--budget", "12", "--out", str(tmp_path), "--workers", "1",
                 "--no-progress"]) == 0
    result = json.loads((tmp_path / "result.json").read_text())
    report = (tmp_path / "report.md").read_text()
    assert "## Stages" not in report and "## The run" in report and result["message"] in report
    # No original design, no column of dashes for savings against it.
    assert "| design | x1 | x2 | x3 | f | feasible |" in report and "savings" not in report
    assert list(result["figures"].values()) == ["figures/progress.png"]
    assert _is_png(tmp_path / "figures" / "progress.png") and len(result["history"]) == 12


def test_rerun_resumes_from_the_store(study_dir, tmp_path, capsys):
    from mechopt.runs.store import SampleStore
    from mechopt.studies.catalogue import load_study

    key = load_study("ventilator", {"engine": "analytic"}).problem.fingerprint()
    with SampleStore(study_dir / "samples.sqlite") as store:
        before = store.count(key)
    # Another output folder, the same store named with --store: everything comes from the store.
    other = tmp_path / "again"
    assert main(["study", "ventilator", "--out", str(other), "--store", str(study_dir / "samples.sqlite"),
                 "--lines", "6", *SMALL]) == 0
    with SampleStore(study_dir / "samples.sqlite") as store:
        assert store.count(key) == before  # nothing simulated twice
    assert not (other / "samples.sqlite").exists() and (other / "result.json").is_file()
    result = json.loads((other / "result.json").read_text())
    assert result["simulations"]["new"] == 0 and result["simulations"]["reused"] == before
    assert "0 new" in capsys.readouterr().out


def test_validate_reuses_the_model(study_dir, capsys):
    # Its plan first, exact with a saved model: the held-out lines are placed without simulating, and the store
    # holds the 6 lines of 8 the study validated on (the same seed places the same lines first).
    assert main(["validate", "--out", str(study_dir), "--lines", "7", "--dry-run", *SMALL]) == 0
    plan = capsys.readouterr().out.splitlines()
    assert plan[0] == "plan: the saved line model, 56 held-out simulations; 1 at a time"
    assert plan[1].startswith("  validate the saved line model: 7 held-out lines of 8: 56 simulations, 48 already in "
                              "the store")
    assert plan[-1] == "dry run: nothing simulated"
    assert main(["validate", "--out", str(study_dir), "--lines", "7", *SMALL]) == 0
    out = capsys.readouterr().out
    assert "model read from" in out and "held-out simulations on 7 lines" in out
    assert out.splitlines()[-1] == "simulations: 8 new, 48 reused from the store, 0 computed by another run"
    # Its own figure: the study's validation figure is not overwritten.
    assert _is_png(study_dir / "figures" / "validation_heldout.png") and _is_png(study_dir / "figures" /
                                                                                  "validation.png")
    # One definition of the reference minimum: the study's best simulated design.
    result = json.loads((study_dir / "result.json").read_text())
    assert json.loads((study_dir / "validation.json").read_text())["f_min"] == result["optimum"]["objective"]


def test_feasible_plots(tmp_path, capsys):
    assert main(["feasible", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "of the region is feasible" in out and "original" in out
    assert _is_png(tmp_path / "figures" / "feasible_slices_all_designs.png", 50_000)
    assert _is_png(tmp_path / "figures" / "feasible_3d_all_designs.png", 50_000)


@pytest.mark.parametrize(
    ("section", "expected"),
    [
        ("n_lines = 'seven'", "surrogate.n_lines"),
        ("lines = 7", "unknown option surrogate.lines"),
        ("plan = 'magic'", "surrogate.plan"),
        ("layout = 'grid'", "surrogate.layout"),
        ("fit = 'log'", "surrogate.fit"),
        ("refine = 'yes'", "surrogate.refine"),
    ],
)
def test_bad_study_keys(tmp_path, capsys, section, expected):
    from mechopt.studies.catalogue import STUDIES_DIR

    text = (STUDIES_DIR / "ventilator" / "study.toml").read_text()
    (tmp_path / "original_design_load_inertia.csv").write_text(
        (STUDIES_DIR / "ventilator" / "original_design_load_inertia.csv").read_text())
    path = tmp_path / "bad.toml"
    # The bad line replaces the study's own line for the same key (TOML forbids a key twice).
    key = section.split("=")[0].strip()
    text = re.sub(rf"^{key} = .*\n", "", text, flags=re.MULTILINE)
    path.write_text(text.replace("[surrogate]\n", "[surrogate]\n" + section + "\n", 1))
    assert main(["study", str(path), "--out", str(tmp_path / "o"), *SMALL]) == EXIT_ERROR
    err = capsys.readouterr().err.strip()
    assert expected in err and "\n" not in err


def test_paper_plan_is_expressible():
    from mechopt.optimize.sparse.space import ModelSpace
    from mechopt.optimize.sparse.stage import paper_plan
    from mechopt.studies.catalogue import load_study
    from mechopt.studies.runner import study_options

    study = load_study("ventilator")
    opts = study_options(study, {"plan": "paper", "samples_per_line": 30, "min_samples": 10})
    plan, coverage = paper_plan(ModelSpace(study.problem), opts)
    np.testing.assert_allclose(plan.direction, [0.0, 0.920, 0.503])
    np.testing.assert_allclose(plan.origin, [31.000, 257.859, 72.705])
    assert 0 < coverage <= 1


def test_every_study_flag_end_to_end(tmp_path, capsys):
    # --no-refine used to fail on every run (the options check rejected every boolean).
    args = ["study", "ventilator", "--out", str(tmp_path / "o"), "--store", str(tmp_path / "s.sqlite"),
            "--engine", "analytic", "--workers", "1", "--no-progress", "--plan", "paper", "--lines-fit", "7",
            "--samples-per-line", "12", "--search-points", "100000", "--budget", "100", "--seed", "2",
            "--no-refine", "--lines", "2", "--points-per-line", "5", "--retry-failed", "--truth",
            "--truth-grid", "4"]
    assert main(args) == 0, capsys.readouterr().err
    result = json.loads((tmp_path / "o" / "result.json").read_text())
    assert [s["name"] for s in result["stages"]] == ["global"]  # no refinement
    assert result["options"]["plan"] == "paper" and result["options"]["seed"] == 2
    assert result["validation"]["n_lines"] == 2 and result["ground_truth"]["grid_step"] == 4
    assert result["simulations"]["optimisation"] <= 100
    out = capsys.readouterr().out
    assert "ground truth" in out and "reused" in out


def test_two_studies_at_once_on_one_store_share_the_work(tmp_path):
    import os
    import subprocess
    import sys

    store = tmp_path / "shared.sqlite"
    cmd = [sys.executable, "-m", "mechopt.cli.main", "study", "ventilator", "--store", str(store), "--lines", "0",
           *SMALL, "--lines-fit", "5", "--samples-per-line", "10", "--budget", "70"]
    env = {**os.environ, "MPLBACKEND": "Agg"}
    procs = [subprocess.Popen([*cmd, "--out", str(tmp_path / f"run{i}")], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for i in range(2)]
    for p in procs:
        _, err = p.communicate(timeout=600)
        assert p.returncode == 0, err
    runs = [json.loads((tmp_path / f"run{i}" / "result.json").read_text())["simulations"] for i in range(2)]
    # Alone, one run simulates all its distinct designs; together the two split them (the store's claims), up to
    # the few designs in flight when one run waits for the other's claim.
    distinct = runs[0]["distinct_designs"]
    assert runs[1]["distinct_designs"] == distinct
    assert runs[0]["new"] + runs[1]["new"] <= distinct + 4
    assert runs[0]["waited_for_other_runs"] + runs[1]["waited_for_other_runs"] + runs[0]["reused"] + \
        runs[1]["reused"] >= distinct - 4
