"""The sparse options of a study run: its ``[surrogate]`` section, the command line's overrides, and a line plan
that fits the budget.

A study's own line plan is sized for its own budget (the ventilator: 21 lines of 25 for 600 simulations).  Under a
smaller ``--budget`` it would take every simulation and leave none to refine, and the answer got worse with more
budget (issue 25: 147 of 150 on the lines, 3 left to refine).  So the plan the study (or the default) declares is
kept only while it fits the lines' share of the budget (:meth:`SparseOptions.line_cap`); otherwise it is scaled to the
budget as :meth:`SparseOptions.for_budget` scales it for :func:`mechopt.minimize`.  A plan given on the command line
(``--lines-fit``, ``--samples-per-line``) is the user's and always kept.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from mechopt.optimize.sparse.options import PLAN_KEYS, SparseOptions
from mechopt.studies.catalogue import Study

__all__ = ["study_options"]

#: Grid points of the exhaustive search when the plan is scaled below 600 simulations (as in ``for_budget``): a
#: small plan's blend does not repay 10 million.
SCALED_SEARCH_POINTS = 2_000_000


def study_options(study: Study, overrides: dict[str, Any] | None = None,
                  log: Callable[[str], None] | None = None) -> SparseOptions:
    """The sparse options of a study: its ``[surrogate]`` section, then the command line's overrides, with the line
    plan scaled to the budget when the declared one does not fit it.

    Parameters
    ----------
    study : Study
        The study (its ``[surrogate]`` section and its problem's dimension).
    overrides : dict, optional
        The command line's values (None: not given).
    log : callable, optional
        Told when the study's line plan is replaced by one scaled to the budget.
    """
    section = dict(study.section("surrogate"))
    given = {k: v for k, v in (overrides or {}).items() if v is not None}
    values = {**section, **given}
    declared = SparseOptions(values, where="surrogate.")  # checks every value before anything is scaled
    scaled = SparseOptions.scaled_plan(declared.budget, study.problem.dim)
    if declared.budget < 600 and "search_points" not in values:
        scaled["search_points"] = SCALED_SEARCH_POINTS
    planned = declared.n_lines * declared.samples_per_line
    by_user = any(k in given for k in PLAN_KEYS)
    if scaled and not by_user and planned > declared.line_cap() and declared.plan == "auto":
        values = {k: v for k, v in values.items() if k not in PLAN_KEYS}
        if log is not None and any(k in section for k in PLAN_KEYS):
            log(f"  the study's line plan ({declared.n_lines} lines x {declared.samples_per_line}) does not fit the "
                f"lines' share of a budget of {declared.budget}: scaled to {scaled['n_lines']} lines x "
                f"{scaled['samples_per_line']} (--lines-fit and --samples-per-line choose it)")
        return SparseOptions({**scaled, **values}, where="surrogate.")
    # The declared plan fits: the scaled search size and order limits only fill in what the study did not set.
    keep = {k: v for k, v in scaled.items() if k == "search_points"}
    return SparseOptions({**keep, **values}, where="surrogate.")
