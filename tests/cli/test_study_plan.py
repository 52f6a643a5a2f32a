"""Issue 25 as a new user meets it: an external-command study of 3 variables (a script that exits 3 where x > 0.85),
its plan before the run, a budget that is the cost, and more budget never worse."""

from __future__ import annotations

import json
import sqlite3

import pytest

from mechopt.cli.main import EXIT_ERROR, main

SIM = """\
import json, math, pathlib, sys
pathlib.Path(__file__).with_name("calls.log").open("a").write("x\\n")
d = json.load(sys.stdin)
x, y, z = d["x"], d["y"], d["z"]
if x > 0.85:
    sys.exit(3)
f = 0.5 * ((x - 0.6) ** 2 + (y - 0.3) ** 2 + (z - 0.7) ** 2) - 0.06 * math.cos(6 * x) * math.cos(5 * y) * math.cos(
    4 * (z - 0.7))
print(json.dumps({"f": f}))
"""

STUDY = """\
name = "my-ext"
description = "A user's expensive simulator behind a command"
kind = "external"
[variables]
x = { lower = 0.0, upper = 1.0, unit = "mm" }
y = { lower = 0.0, upper = 1.0, unit = "mm" }
z = { lower = 0.0, upper = 1.0, unit = "mm" }
[simulator]
command = ["{python}", "sim.py"]
outputs = ["f"]
timeout_s = 30
"""


def write_study(folder, seconds_per_run="85"):
    (folder / "sim.py").write_text(SIM)
    toml = folder / "study.toml"
    toml.write_text(STUDY + (f"seconds_per_run = {seconds_per_run}\n" if seconds_per_run is not None else ""))
    return toml


def _calls(folder) -> int:
    log = folder / "calls.log"
    return len(log.read_text().splitlines()) if log.is_file() else 0


def _stored(store) -> int:
    with sqlite3.connect(store) as db:
        return db.execute("SELECT COUNT(*) FROM samples").fetchone()[0]


def _run(toml, out, budget, capsys, *extra):
    code = main(["study", str(toml), "--out", str(out), "--workers", "2", "--no-progress", "--budget", str(budget),
                 *extra])
    text = capsys.readouterr().out
    assert code == 0, text
    return text, json.loads((out / "result.json").read_text())


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The study at budgets 60 and 150, each on its own store (their stdout, result.json and store)."""
    folder = tmp_path_factory.mktemp("ext")
    toml = write_study(folder)
    capsys = _Capture()
    out = {}
    for budget in (60, 150):
        with capsys:
            code = main(["study", str(toml), "--out", str(folder / f"out{budget}"), "--workers", "2",
                         "--no-progress", "--budget", str(budget), "--method", "sparse"])
        assert code == 0, capsys.text
        out[budget] = (capsys.text, json.loads((folder / f"out{budget}" / "result.json").read_text()),
                       folder / f"out{budget}" / "samples.sqlite")
    return folder, toml, out


class _Capture:
    """stdout of a module-scoped run (capsys is function-scoped)."""

    def __enter__(self):
        import contextlib
        import io

        self._buffer = io.StringIO()
        self._redirect = contextlib.redirect_stdout(self._buffer)
        self._redirect.__enter__()
        return self

    def __exit__(self, *exc):
        self._redirect.__exit__(*exc)
        self.text = self._buffer.getvalue()


def test_dry_run_prints_the_plan_and_simulates_nothing(tmp_path, capsys):
    toml = write_study(tmp_path)
    out = tmp_path / "out"
    assert main(["study", str(toml), "--out", str(out), "--workers", "2", "--budget", "60", "--method", "sparse",
                 "--dry-run"]) == 0
    text = capsys.readouterr().out
    assert _calls(tmp_path) == 0 and not out.exists()  # no simulation, no store, no folder
    assert "study my-ext: A user's expensive simulator behind a command" in text and "ExternalProblem" not in text
    assert "x in [0, 1] mm" in text and "`{python} sim.py`" in text
    assert "global model: 3 lines: 12 simulations" in text and "confirm the model's candidate: 1 simulation" in text
    assert "refine: model steps: up to 12 simulations (6 rounds of 2)" in text
    assert "corrected steps: up to 35 simulations (18 rounds of 2)" in text
    assert "validate: 2 held-out lines of 6: up to 12" in text
    # 12 lines on 2 workers: 6 rounds; 1; the refinement's 47 in batches of 2 (issue 28): 6 + 18 rounds; 12 held
    # out: 6 rounds -> 37 x 85 s = 52 min.
    assert "at most 72 designs, 72 to simulate; expected simulation time about 52 min on 2 workers (37 rounds" in text
    assert "85 s a simulation, declared in [simulator] seconds_per_run" in text


def test_a_bad_declared_cost_is_one_line_before_any_simulation(tmp_path, capsys):
    toml = write_study(tmp_path, seconds_per_run="-3")
    assert main(["study", str(toml), "--out", str(tmp_path / "o"), "--budget", "60"]) == EXIT_ERROR
    err = capsys.readouterr().err.strip()
    assert "simulator.seconds_per_run = -3 must be > 0" in err and len(err.splitlines()) == 1
    assert _calls(tmp_path) == 0


def test_budget_60_costs_at_most_72_designs_and_says_so(runs):
    folder, _, out = runs
    text, result, store = out[60]
    sims = result["simulations"]
    assert sims["optimisation"] <= 60 and sims["validation"] <= 12
    assert _stored(store) <= 72 and sims["distinct_designs"] <= 72
    assert "budget 60" in text and "on top of the budget: 20% of it" in text
    assert result["budget"] == 60 and result["plan"]["total"] == 72
    # Issue 28: the rounds of simulations, the workers' idle share, waiting and the method's own time.
    assert sims["rounds"] < sims["new"] and 0 <= sims["idle_share"] <= 1 and sims["workers"] == 2
    assert sims["optimisation_timing"]["rounds"] <= sims["rounds"] and result["plan"]["rounds"] < 72
    assert "rounds of simulations on 2 workers (idle" in text and "s of the method's own computing" in text
    # Rounds as the plan counts them (simulations one after the other, 2 at a time), not the method's calls.
    assert f"; {sims['waves']} rounds of simulations on 2 workers" in text and sims["waves"] >= sims["rounds"]
    report = (store.parent / "report.md").read_text()
    assert "on top of the budget, 20% of it" in report and ".." not in report.replace("../", "")
    # Errors against the range of the values, never a percentage of a best value near 0.
    assert "of the best simulated value" not in report and "% of the held-out values' range" in report
    assert "--method sparse-global" in result["trust"]["verdict"] or result["trust"]["resolved"]


def test_more_budget_is_not_worse_through_the_command(runs):
    _, _, out = runs
    assert out[150][1]["optimum"]["objective"] <= out[60][1]["optimum"]["objective"]
    assert out[150][1]["simulations"]["optimisation"] <= 150


def test_the_plan_of_a_resumed_store_counts_what_it_holds(runs, capsys):
    folder, toml, out = runs
    before = _calls(folder)
    assert main(["study", str(toml), "--out", str(folder / "out60"), "--workers", "1", "--budget", "60",
                 "--method", "sparse", "--dry-run"]) == 0
    text = capsys.readouterr().out
    assert _calls(folder) == before
    # Same seed, same plan: the 12 line designs are in the store, and the cost is the store's measured median.
    assert "12 simulations, 12 already in the store" in text and "recorded in the store; declared 85 s" in text
