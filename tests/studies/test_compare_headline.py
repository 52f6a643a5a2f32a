"""The headline's count: the budget from which on a method's median run stays at the optimum."""

from mechopt.studies.compare import headline, largest_budgets, simulations_needed


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
