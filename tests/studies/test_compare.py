"""``mechopt compare`` on a small configuration: table from code, budgets respected, scored against the truth."""

import json

import numpy as np
import pytest

from mechopt.studies.cli import EXIT_ERROR, main


def test_compare_small(tmp_path, capsys):
    args = ["compare", "--budgets", "40,60", "--seeds", "2", "--out", str(tmp_path), "--truth-grid", "2",
            "--methods", "mechopt,differential_evolution,slsqp,sce_ua"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "| mechopt | 40 |" in out and "| slsqp | 60 |" in out
    data = json.loads((tmp_path / "compare.json").read_text())
    truth = data["truth"]["fun"]
    for run in data["runs"]:
        assert run["nfev"] <= run["budget"], run  # budget accounting
        if run["x"] is not None:
            assert run["value"] >= truth * (1 - 1e-6)  # nobody beats the ground truth
            assert run["gap_pct"] == pytest.approx(100 * (run["value"] / truth - 1))
    assert {r["method"] for r in data["rows"]} == {"mechopt", "differential_evolution", "slsqp", "sce_ua"}
    png = (tmp_path / "figures" / "compare_gaps.png").read_bytes()
    assert png[:4] == b"\x89PNG" and len(png) > 20_000
    # Seeded: the same command gives the same table.
    assert main(args) == 0
    again = json.loads((tmp_path / "compare.json").read_text())
    np.testing.assert_allclose([r["median_value"] for r in again["rows"]], [r["median_value"] for r in data["rows"]])


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
