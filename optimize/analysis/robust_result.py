"""What :func:`mechopt.minimize` does with ``tolerances=``: the arguments checked before any simulation, and the
robust optimum put in the result in place of the nominal one (which stays beside it)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from mechopt.optimize.analysis.robust import robust_optimum
from mechopt.optimize.analysis.scatter import Tolerances, as_tolerances, check_max_violation
from mechopt.optimize.problem import DesignProblem

__all__ = ["checked_robust", "make_robust", "make_study_robust"]


def checked_robust(problem: DesignProblem, tolerances: Any, max_violation: Any) -> Tolerances | None:
    """The tolerances of a call, checked with its target probability (None: no robust optimum asked)."""
    if tolerances is None:
        return None
    tol = as_tolerances(tolerances, problem)
    check_max_violation(max_violation)
    return tol


def make_robust(problem: DesignProblem, result: Any, sampler: Any, tolerances: Tolerances | None,
                max_violation: float, log: Callable[[str], None]) -> None:
    """Replace ``result.x`` and ``result.fun`` by the robust optimum; the nominal one goes to ``nominal_x`` and
    ``nominal_fun``, the comparison to ``robust`` (:class:`~mechopt.optimize.analysis.robust.RobustOptimum`).
    Nothing without tolerances, or when the run found no design."""
    if tolerances is None or not result.success:
        return
    log(f"robust optimum: {tolerances.describe(problem)}, each margin violated with probability <= {max_violation}")
    robust = robust_optimum(problem, sampler, np.asarray(result.x, dtype=float), tolerances, max_violation,
                            budget=tolerances.robust_simulations, log=log)
    for line in robust.lines(problem):
        log(f"  {line}")
    result.update(nominal_x=robust.nominal_x, nominal_fun=robust.nominal_fun, robust=robust, x=robust.x,
                  fun=robust.fun)
    result["outputs"] = dict(sampler.records(robust.x[None, :], desc="robust optimum")[0].outputs)


def make_study_robust(study: Any, result: Any, sampler: Any, log: Callable[[str], None]) -> None:
    """:func:`make_robust` with a study's ``[tolerances]``, when it sets ``max_violation``."""
    declared = getattr(study, "tolerances", None)
    if declared is not None and declared.max_violation is not None:
        make_robust(study.problem, result, sampler, declared.tolerances, declared.max_violation, log)
