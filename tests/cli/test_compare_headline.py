"""The headline's count: the budget from which on a method's median run stays at the optimum."""

from mechopt.studies.comparison import headline, largest_budgets, simulations_needed


def test_simulations_needed_counts_from_where_the_median_stays_reached():
    rows = [{"method": m, "budget": b, "median_reached": r} for m, b, r in [
        ("steady", 10, False), ("steady", 20, True), ("steady", 40, True),
        ("lucky", 10, True), ("lucky", 20, False), ("lucky", 40, True),
        ("lost", 10, True), ("lost", 20, True), ("lost", 40, False),
        ("never", 10, False), ("never", 20, False), ("never", 40, False)]]
    assert simulations_needed(rows) == {"steady": 20, "lucky": 40, "lost": None, "never": None}
    text = headline({"study": simulations_needed(rows)}, {"study": 40})
    assert "| steady | 20 |" in text and "| lost | > 40 |" in text


def test_a_method_capped_below_the_others_is_reported_against_its_own_largest_budget():
    rows = [{"method": "ego", "budget": 30, "median_reached": False}, {"method": "ego", "budget": 60,
            "median_reached": False}, {"method": "de", "budget": 300, "median_reached": False}]
    text = headline({"f": simulations_needed(rows)}, {"f": largest_budgets(rows)})
    assert "| ego | > 60 |" in text and "| de | > 300 |" in text


def test_merge_replaces_one_methods_runs_and_recounts(tmp_path, monkeypatch):
    # benchmarks/compare_merge.py: the newer file's method replaces the base's; the others are kept; the table and
    # the count are made anew from the merged runs.
    import json
    import sys

    from benchmarks import compare_merge
    from mechopt.studies import comparison as cmp
    from mechopt.studies.catalogue import load_study

    study = load_study("branin", {})
    truth = cmp.known_truth(study.problem)
    x = list(map(float, truth.x))

    def run(method, budget, value):
        return cmp.Run(method, budget, 0, x, value, cmp.gap_pct(study.problem, truth, value), budget, 0.1)

    far, near = truth.fun + 50.0, truth.fun + 1e-6
    cmp.write([run("a", 30, far), run("a", 60, far), run("b", 30, far), run("b", 60, near)], truth,
              tmp_path / "base", study, 1)
    cmp.write([run("a", 30, near), run("a", 60, near)], truth, tmp_path / "new", study, 1)
    monkeypatch.setattr(sys, "argv", ["compare_merge", str(tmp_path / "base" / "compare.json"),
                                      str(tmp_path / "new" / "compare.json"), "--out", str(tmp_path / "merged")])
    compare_merge.main()
    merged = json.loads((tmp_path / "merged" / "compare.json").read_text())
    assert merged["needed"] == {"a": 30, "b": 60}
    assert sorted((r["method"], r["budget"], r["value"]) for r in merged["runs"]) == [
        ("a", 30, near), ("a", 60, near), ("b", 30, far), ("b", 60, near)]
    assert (tmp_path / "merged" / "compare.md").is_file()
