"""A study whose answer is worse than one of its own reference designs says so (issue 52)."""

from __future__ import annotations

import json
import math

from mechopt.cli.main import main
from mechopt.studies.reference_check import better_references, reference_warning

REFS = {
    "original": {"status": "ok", "feasible": True, "outputs": {"E": 3.0}},
    "best_found": {"status": "ok", "feasible": True, "outputs": {"E": 0.032}},
    "infeasible": {"status": "ok", "feasible": False, "outputs": {"E": 0.001}},
    "failed": {"status": "failed", "feasible": True, "outputs": {}},
    "optimum": {"status": "ok", "feasible": True, "outputs": {"E": 1.22}},
}


def test_only_simulated_feasible_better_references_count_best_first():
    assert better_references(REFS, "E", 1.22) == [("best_found", 0.032)]
    assert better_references(REFS, "E", 5.0) == [("best_found", 0.032), ("original", 3.0)]
    assert better_references(REFS, "E", 0.032) == []  # a tie is no warning
    assert better_references(REFS, "E", math.nan) == [("best_found", 0.032), ("original", 3.0)]
    line = reference_warning(REFS, "E", 1.22, "mm")
    assert line == ("warning: this answer (E 1.22 mm) is worse than the study's own reference design 'best_found' "
                    "(E 0.032 mm, 38.1 times lower): the run missed a better design; try a larger budget, another "
                    "method, or start from it with --x0")
    assert reference_warning(REFS, "E", 0.01) is None


def test_path_synthesis_2_says_so_in_its_last_line_and_its_report(tmp_path, capsys):
    out = tmp_path / "ps2"
    code = main(["study", "path-synthesis-2", "--budget", "18", "--method", "auto", "--workers", "1",
                 "--no-progress", "--out", str(out)])
    assert code == 0
    printed = capsys.readouterr().out.strip().splitlines()
    warning = printed[-2]
    assert warning.startswith("warning: this answer (E ") and "reference design 'best_found' (E 0.0324" in warning
    assert printed[-1].startswith("report: ")
    result = json.loads((out / "result.json").read_text())
    assert result["reference_warning"] == printed[-2]
    assert f"**W{printed[-2][1:]}**" in (out / "report.md").read_text()
