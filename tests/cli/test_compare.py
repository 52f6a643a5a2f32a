"""``mechopt compare`` on a small configuration: table from code, budgets respected, scored against the truth."""

import json

import numpy as np
import pytest

from mechopt.cli.main import EXIT_ERROR, main


def test_compare_small(tmp_path, capsys):
    args = ["compare", "--budgets", "30,40", "--seeds", "2", "--out", str(tmp_path), "--truth-grid", "2",
            "--methods", "mechopt,differential_evolution,slsqp"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "| mechopt | 30 |" in out and "| slsqp | 40 |" in out
    data = json.loads((tmp_path / "compare.json").read_text())
    truth = data["truth"]["fun"]
    for run in data["runs"]:
        assert run["nfev"] <= run["budget"], run  # budget accounting
        if run["x"] is not None:
            assert run["value"] >= truth * (1 - 1e-6)  # nobody beats the ground truth
            assert run["gap_pct"] == pytest.approx(100 * (run["value"] / truth - 1))
    assert {r["method"] for r in data["rows"]} == {"mechopt", "differential_evolution", "slsqp"}
    png = (tmp_path / "figures" / "compare_gaps.png").read_bytes()
    assert png[:4] == b"\x89PNG" and len(png) > 20_000
    # Seeded: the same run again gives the same design and value.
    again_args = ["compare", "--budgets", "30", "--seeds", "1", "--out", str(tmp_path / "again"), "--truth-grid", "2",
                  "--methods", "mechopt,slsqp"]
    assert main(again_args) == 0
    again = json.loads((tmp_path / "again" / "compare.json").read_text())["runs"]
    for run in again:
        first = next(r for r in data["runs"] if (r["method"], r["budget"], r["seed"]) ==
                     (run["method"], run["budget"], run["seed"]))
        np.testing.assert_allclose(run["value"], first["value"])


@pytest.mark.parametrize(("args", "expected"), [(["--budgets", "5"], "expected integers >= 10"),
                                                (["--methods", "magic"], "unknown method 'magic'")])
def test_compare_bad_input(tmp_path, capsys, args, expected):
    code = None
    try:
        code = main(["compare", "--out", str(tmp_path), "--truth-grid", "2", "--seeds", "1", *args])
    except SystemExit as exc:  # argparse rejects malformed values itself, with a one-line usage error
        code = exc.code
    assert code in (EXIT_ERROR, 2)
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert expected in err


def test_headline_across_studies_with_known_optima(tmp_path, capsys):
    # Test functions load as studies; their optimum is known, so no brute force: the headline table counts the
    # simulations after which the median run is within 0.5 % of the function's range.
    args = ["compare", "--study", "branin,six_hump_camel", "--budgets", "30,60", "--seeds", "2", "--out",
            str(tmp_path), "--methods", "mechopt,slsqp"]
    assert main(args) == 0
    headline = (tmp_path / "headline.md").read_text()
    assert "| method | branin | six_hump_camel |" in headline and "| mechopt |" in headline
    data = json.loads((tmp_path / "branin" / "compare.json").read_text())
    assert data["truth"]["key"] == "known" and data["tolerance"] == pytest.approx(0.005 * 307.73)
    assert (tmp_path / "figures" / "compare_headline.png").read_bytes()[:4] == b"\x89PNG"
