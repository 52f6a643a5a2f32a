"""Optimizer comparison at equal simulation budgets on a study (``mechopt compare``): the runs
(:mod:`~mechopt.studies.comparison.engine`), how each is scored (:mod:`~mechopt.studies.comparison.score`) and the
tables and files (:mod:`~mechopt.studies.comparison.tables`); its figures are in :mod:`mechopt.report`."""

from mechopt.studies.comparison.engine import (
    OWN_METHOD,
    Run,
    check_limits,
    check_methods,
    compare,
    compared_methods,
    method_caps,
    method_names,
    run_one,
    true_objective,
)
from mechopt.studies.comparison.score import declared_truth, gap_measure, gap_pct, known_truth, tolerance
from mechopt.studies.comparison.tables import (
    UNFINISHED_MARK,
    headline,
    largest_budgets,
    markdown,
    pivot_markdown,
    simulations_needed,
    table,
    unfinished_methods,
    unfinished_runs,
    write,
    write_headline,
)

__all__ = ["OWN_METHOD", "UNFINISHED_MARK", "Run", "check_limits", "check_methods", "compare", "compared_methods",
           "declared_truth", "gap_measure", "gap_pct", "headline", "known_truth", "largest_budgets", "markdown",
           "method_caps", "method_names", "pivot_markdown", "run_one", "simulations_needed", "table",
           "tolerance", "true_objective", "unfinished_methods", "unfinished_runs", "write",
           "write_headline"]
