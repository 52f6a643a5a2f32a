"""The ``[tolerances]`` table of a study file: ± per variable in its unit, how they are read, and the robust
optimum's target.

    [tolerances]
    oa = 0.1                  # ± mm; a variable not named is made exactly
    ab = 0.1
    bc = 0.1
    distribution = "uniform"  # or "normal" (the tolerance is 3σ)
    max_violation = 0.01      # a robust optimum: each margin violated on at most 1 % of the parts
    statistic = "mean"        # what it minimises over the scatter, or a quantile level such as 0.95
    robust_simulations = 40   # most simulations it adds to the nominal run
"""

from __future__ import annotations

from dataclasses import dataclass

from mechopt.errors import InputError, StudyError
from mechopt.optimize.analysis.scatter import DISTRIBUTIONS, Tolerances
from mechopt.optimize.problem import DesignProblem
from mechopt.studies.study_file import StudyFile

__all__ = ["StudyTolerances", "read_tolerances"]

_OPTIONS = ("distribution", "max_violation", "statistic", "robust_simulations")


@dataclass(frozen=True)
class StudyTolerances:
    """A study's tolerances and, when ``max_violation`` is set, its robust optimum's target (None: analysis only)."""

    tolerances: Tolerances
    max_violation: float | None = None


def read_tolerances(file: StudyFile, problem: DesignProblem) -> StudyTolerances | None:
    """The ``[tolerances]`` table, checked (None when the study has none)."""
    table = file.table("tolerances", allowed=(*problem.names, *_OPTIONS), required=False)
    if not table:
        return None
    values = {n: file.number(table, n, "tolerances", minimum=0.0) for n in problem.names if n in table}
    statistic = table.get("statistic", "mean")
    if not isinstance(statistic, str):
        statistic = file.number(table, "statistic", "tolerances")
    target = None if "max_violation" not in table else file.number(table, "max_violation", "tolerances")
    try:
        tol = Tolerances(values, distribution=file.string(table, "distribution", "tolerances", "uniform",
                                                          DISTRIBUTIONS),
                         statistic=statistic,
                         robust_simulations=file.integer(table, "robust_simulations", "tolerances", 40, 0))
        tol.vector(problem)
        if target is not None and not 0.0 < target < 0.5:
            raise InputError(f"max_violation = {target!r}: expected a probability in (0, 0.5), such as 0.01")
    except InputError as exc:
        raise StudyError(f"{file.where}: [tolerances]: {exc}") from None
    return StudyTolerances(tol, target)
