"""Every CLI command end to end on a small configuration, and figures that are real images."""

import json
import re

import numpy as np
import pytest
from mechopt.studies.cli import EXIT_ERROR, main

SMALL = ["--engine", "analytic", "--workers", "1", "--no-progress", "--samples-per-line", "24",
         "--search-points", "200000", "--points-per-line", "8"]


@pytest.fixture(scope="module")
def study_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    assert main(["study", "ventilator", "--out", str(out), "--lines", "6", "--truth-grid", "2", *SMALL]) == 0
    return out


def _is_png(path, min_bytes=10_000):
    data = path.read_bytes()
    return data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > min_bytes


def test_study_writes_result_report_and_figures(study_dir):
    result = json.loads((study_dir / "result.json").read_text())
    assert result["simulations"]["fit"] < 618
    assert result["validation"]["n_points"] >= 40
    # The global model (21 lines at Fekete nodes, blended T_RMS²) on held-out lines: RMSE within 1 % of T_min.
    assert result["validation"]["rmse_Nm"] <= 0.01 * result["ground_truth"]["t_rms_Nm"], result["validation"]
    opt = result["optimum"]
    assert opt["t_rms_Nm"] < 0.5 * result["designs"][0]["t_rms_Nm"]  # far better than the original
    # Within 0.5 % of the brute-force ground truth even in this small configuration.
    assert result["ground_truth"]["gap_pct"] < 0.5
    report = (study_dir / "report.md").read_text()
    assert "| original |" in report and "paper_global_optimum" in report
    for rel in result["figures"].values():
        path = study_dir / rel
        assert path.is_file() and path.stat().st_size > 10_000, rel
        if rel.endswith(".png"):
            assert _is_png(path)
        elif rel.endswith(".gif"):
            assert path.read_bytes()[:6] in (b"GIF87a", b"GIF89a")
    assert (study_dir / "samples.sqlite").is_file() and (study_dir / "model.json").is_file()


def test_rerun_resumes_from_the_store(study_dir, tmp_path, capsys):
    from mechopt.studies.definition import load_study
    from mechopt.studies.evaluate import Evaluator
    from mechopt.studies.store import SampleStore

    study = load_study("ventilator")
    key = Evaluator(study.mechanism, "analytic", study.name).settings_hash()
    with SampleStore(study_dir / "samples.sqlite") as store:
        before = store.count(key)
    # Another output folder, the same store named with --store: everything comes from the store.
    other = tmp_path / "again"
    assert main(["study", "ventilator", "--out", str(other), "--store", str(study_dir / "samples.sqlite"),
                 "--lines", "6", "--truth-grid", "2", *SMALL]) == 0
    with SampleStore(study_dir / "samples.sqlite") as store:
        assert store.count(key) == before  # nothing simulated twice
    assert not (other / "samples.sqlite").exists() and (other / "result.json").is_file()


def test_validate_reuses_the_model(study_dir, capsys):
    assert main(["validate", "--out", str(study_dir), "--lines", "2", *SMALL]) == 0
    out = capsys.readouterr().out
    assert "model read from" in out and "held-out simulations on 2 lines" in out
    assert _is_png(study_dir / "figures" / "validation.png")


def test_feasible_plots(tmp_path, capsys):
    assert main(["feasible", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "of the region is feasible" in out and "original" in out
    assert _is_png(tmp_path / "figures" / "feasible_slices.png", 50_000)
    assert _is_png(tmp_path / "figures" / "feasible_3d.png", 50_000)


@pytest.mark.parametrize(
    ("section", "expected"),
    [
        ("n_lines = 'seven'", "surrogate.n_lines"),
        ("lines = 7", "unknown key surrogate.lines"),
        ("plan = 'magic'", "surrogate.plan"),
        ("layout = 'grid'", "surrogate.layout"),
        ("target = 'log'", "surrogate.target"),
    ],
)
def test_bad_study_keys(tmp_path, capsys, section, expected):
    from mechopt.studies.definition import STUDIES_DIR

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
    from mechopt.studies.definition import load_study
    from mechopt.studies.design_space import DesignSpace
    from mechopt.studies.workflow import SurrogateOptions, _paper_plan

    study = load_study("ventilator")
    opts = SurrogateOptions(plan="paper", samples_per_line=30, min_samples=10)
    plan, coverage = _paper_plan(DesignSpace(study.mechanism, study.region), opts)
    np.testing.assert_allclose(plan.direction, [0.0, 0.920, 0.503])
    np.testing.assert_allclose(plan.origin, [31.000, 257.859, 72.705])
    assert 0 < coverage <= 1
