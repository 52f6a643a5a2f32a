"""``mechopt compare`` on a small configuration: table from code, budgets respected, scored against the truth."""

import json

import numpy as np
import pytest

from mechopt.cli.main import EXIT_ERROR, main
from mechopt.errors import InputError


def test_compare_small(tmp_path, capsys):
    # The default method's runs dominate this test's time: one budget of it, two of the cheap peers' budgets.
    args = ["compare", "--budgets", "20,30", "--seeds", "1", "--out", str(tmp_path), "--truth-grid", "2",
            "--methods", "mechopt,differential_evolution,slsqp"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "| mechopt | 30 |" in out and "| slsqp | 20 |" in out
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
    again_args = ["compare", "--budgets", "20", "--seeds", "1", "--out", str(tmp_path / "again"), "--truth-grid", "2",
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


# --------------------------------------------------------------------------- runs that stop before their budget
class PeerDefect(RuntimeError):
    """What a library's defect looks like to the comparison: an exception in the middle of a run."""


def _branin_designs(problem, n: int, seed: int) -> np.ndarray:
    # The first design is a global minimiser of Branin (f* = 0.3979): a run that stops after it "reached" the
    # optimum, so only the rule that unfinished runs are not counted keeps it out of the headline.
    rest = problem.sample_feasible(n - 1, np.random.default_rng(seed))
    return np.vstack([[np.pi, 2.275], rest])


def flaky_peer(problem, seed: int):
    """Test-only baseline: simulates designs one by one and raises at its 5th when seed is 0."""
    for i, x in enumerate(_branin_designs(problem, problem.budget, seed)):
        if seed == 0 and i == 4:
            raise PeerDefect("only 0-dimensional arrays can be converted to Python scalars")
        problem.evaluate(x if seed == 0 else x + [0.0, 0.1 * (i == 0)])  # seed 1 misses the minimiser
    return problem.result("budget spent")


def quiet_peer(problem, seed: int):
    """Test-only library peer that stops after 5 simulations without an error (a wrapper swallowing one)."""
    for x in _branin_designs(problem, 5, seed):
        problem.evaluate(x)
    return problem.result("stopped quietly")


@pytest.fixture
def test_only_peers(monkeypatch):
    from mechopt.optimize.methods import METHODS, Method

    # Two records in the table of methods, which `mechopt compare` and `mechopt.minimize` read; quiet_peer counts as
    # a library peer, one that must spend its whole budget.
    monkeypatch.setitem(METHODS, "flaky_peer", Method("flaky_peer", flaky_peer, "test only"))
    monkeypatch.setitem(METHODS, "quiet_peer", Method("quiet_peer", quiet_peer, "test only", spends_whole_budget=True))


def test_a_peer_failing_part_way_is_marked_and_not_counted(tmp_path, capsys, test_only_peers):
    args = ["compare", "--study", "branin", "--budgets", "20", "--seeds", "2", "--out", str(tmp_path), "--methods",
            "slsqp,flaky_peer,quiet_peer"]
    assert main(args) == 0
    out = capsys.readouterr().out
    # Printed as it happens, with the simulations spent and the reason.
    assert ("flaky_peer at budget 20, seed 0: 4 of 20 simulations, stopped before its budget (raised PeerDefect: "
            "only 0-dimensional arrays") in out
    assert "flaky_peer at budget 20, seed 1: 20 of 20 simulations," in out
    assert "quiet_peer at budget 20, seed 0: 5 of 20 simulations, stopped before its budget (ended with 15" in out
    assert "slsqp at budget 20, seed 0:" in out and "of 20 simulations" in out

    data = json.loads((tmp_path / "compare.json").read_text())
    runs = {(r["method"], r["seed"]): r for r in data["runs"]}
    flaky0, flaky1 = runs["flaky_peer", 0], runs["flaky_peer", 1]
    assert (flaky0["nfev"], flaky0["finished"]) == (4, False) and "PeerDefect" in flaky0["reason"]
    assert flaky0["value"] == pytest.approx(0.397887, abs=1e-5)  # it had found the optimum before it failed
    assert (flaky1["nfev"], flaky1["finished"], flaky1["reason"]) == (20, True, "")
    assert all(not runs["quiet_peer", s]["finished"] and runs["quiet_peer", s]["nfev"] == 5 for s in (0, 1))
    assert all(runs["slsqp", s]["finished"] for s in (0, 1))

    rows = {r["method"]: r for r in data["rows"]}
    # The median is the finished run's alone: the failed run's optimum is not in it.
    assert rows["flaky_peer"]["median_value"] == pytest.approx(flaky1["value"])
    assert flaky1["value"] > flaky0["value"] + 1e-3
    assert (rows["flaky_peer"]["unfinished"], rows["flaky_peer"]["complete"]) == (1, False)
    assert (rows["quiet_peer"]["unfinished"], rows["slsqp"]["unfinished"]) == (2, 0)
    # quiet_peer's first design is the optimum in both runs, yet it never counts as having reached it.
    assert runs["quiet_peer", 0]["gap_pct"] == pytest.approx(0.0, abs=1e-4)
    assert data["needed"]["quiet_peer"] is None and data["needed"]["flaky_peer"] is None
    assert data["unfinished_methods"] == ["flaky_peer", "quiet_peer"]

    md = (tmp_path / "compare.md").read_text()
    assert "| flaky_peer | 20 | 2 |" in md and "| 1 † |" in md and "| 2 † |" in md
    assert "| quiet_peer | 20 | 2 | — | — | — | 0.397887 | — | — |" in md  # nothing finished: only f* to show
    assert "3 run(s) stopped before spending their budget and are not counted" in md
    assert "- flaky_peer at budget 20, seed 0: 4 of 20 simulations, stopped before its budget (raised" in md
    assert "| flaky_peer | " in md.split("Median gap")[1] and ") † |" in md.split("Median gap")[1]


def test_every_compare_table_states_its_measure_and_shows_f_and_f_star(tmp_path):
    # DE on Branin at 20 simulations: a gap of a fraction of a per cent of the range (308) can be f three times f*;
    # the tables say what the gap is a percentage of and show f and f* beside it.
    from mechopt.studies import comparison as cmp
    from mechopt.studies.catalogue import load_study

    study = load_study("branin", {})
    truth = cmp.known_truth(study.problem)
    runs = cmp.compare(study, truth, [20], 1, ["differential_evolution"], progress=lambda _line: None)
    md_path, _ = cmp.write(runs, truth, tmp_path, study, 1)
    md = md_path.read_text()
    value = runs[0].value
    assert value > truth.fun
    assert runs[0].gap_pct == pytest.approx(100 * (value - truth.fun) / study.problem.f_range)
    assert "Gap: % of the range of f over the box (307.7): 100 (f - f*) / range." in md
    header = next(line for line in md.splitlines() if line.startswith("| method | budget"))
    assert "| median f | best f | worst f | f* | median gap (% of the range of f) |" in header
    row = next(line for line in md.splitlines() if line.startswith("| differential_evolution | 20 |"))
    assert f"| {value:.6g} | {value:.6g} | {value:.6g} | {truth.fun:.6g} | {runs[0].gap_pct:+.2f} % |" in row
    pivot = md.split("Median gap to the optimum f* = 0.397887 (% of the range of f over the box")[1]
    assert f"| differential_evolution | {runs[0].gap_pct:+.2f} % (f {value:.4g}) |" in pivot


def test_the_headline_marks_methods_with_unfinished_runs():
    from mechopt.studies.comparison import headline, unfinished_methods

    rows = [{"method": "peer", "budget": 30, "median_reached": True, "complete": False},
            {"method": "ours", "budget": 30, "median_reached": True, "complete": True}]
    assert unfinished_methods(rows) == {"peer"}
    text = headline({"f": {"peer": None, "ours": 30}}, {"f": 30}, {"f": unfinished_methods(rows)})
    assert "| peer | > 30 † |" in text and "| ours | 30 |" in text and "not counted" in text
    assert "†" not in headline({"f": {"peer": None, "ours": 30}}, {"f": 30})


def test_smt_ego_beyond_its_limit_is_refused_in_one_line(tmp_path, capsys):
    from mechopt.optimize.baselines.smt_ego import max_budget as ego_max_budget
    from mechopt.studies.comparison import check_methods

    limit = ego_max_budget(2)  # Branin's 2 variables
    code = main(["compare", "--study", "branin", "--out", str(tmp_path), "--seeds", "1", "--budgets",
                 f"20,{limit + 1}", "--methods", "slsqp,smt_ego"])
    assert code == EXIT_ERROR
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"smt_ego at budget {limit + 1}" in err[0] and f"limit of {limit} simulations" in err[0]
    assert not (tmp_path / "compare.json").exists()  # refused before any run
    # The limit falls with the dimension; capping EGO with --gp-max-budget at or below it skips larger budgets.
    assert ego_max_budget(8) < ego_max_budget(3)
    with pytest.raises(InputError, match=f"limit of {ego_max_budget(8)} simulations at 8 variables"):
        check_methods(["smt_ego"], [ego_max_budget(8) + 1], dims=[2, 8])
    assert check_methods(["smt_ego"], [500], gp_max_budget=ego_max_budget(8), dims=[8]) == ["smt_ego"]
    assert "smt_ego" in check_methods(None, [500], dims=[8])  # every method: skipped beyond, not refused


def test_a_line_model_named_for_a_study_it_cannot_take_is_refused():
    from mechopt.studies.comparison import check_methods

    with pytest.raises(InputError, match="--methods mechopt-global: method 'sparse-global' handles 2 to 4"):
        check_methods(["mechopt-global"], [60], dims=[6])
    assert check_methods(["mechopt-global"], [60], dims=[3]) == ["mechopt-global"]


def test_a_run_refused_for_its_budget_is_marked_with_the_reason():
    # Hartmann-4's line plan needs 11 simulations: at 10 the run is refused, and the table says so (it showed an
    # unexplained infinite gap); at 11 it runs.
    from mechopt.studies.catalogue import load_study
    from mechopt.studies.comparison import known_truth, run_one

    problem = load_study("hartmann4").problem
    truth = known_truth(problem)
    refused = run_one(problem, truth, "mechopt-sparse", 10, 0)
    assert not refused.finished and refused.nfev == 0
    assert refused.reason.startswith("refused: InputError: budget = 10") and "= 11 simulations" in refused.reason
    ran = run_one(problem, truth, "mechopt-sparse", 11, 0)
    assert ran.finished and 0 < ran.nfev <= 11


def test_methods_by_the_names_study_and_minimize_give_them():
    # `mechopt study --method auto` and then `mechopt compare --methods auto` was "unknown method 'auto'".
    from mechopt.studies.comparison import check_methods, method_names

    assert method_names("auto,sparse,sparse-global,smt_ego") == ["mechopt-auto", "mechopt-sparse", "mechopt-global",
                                                                 "smt_ego"]
    assert method_names(None) is None and method_names("mechopt,") == ["mechopt"]
    assert check_methods(method_names("auto,smt_ego"), [30], dims=[3]) == ["mechopt-auto", "smt_ego"]
