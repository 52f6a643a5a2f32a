"""How a compared run is scored: the optimum it is measured against, and the gap to it in stated units.

The reference is the optimum a problem declares (test functions), the one a study file records, or a brute force.
The gap is a percentage of the function's range over the box where the problem declares that range (the test
functions: on Branin, whose range is 308, f 1.19 against f* 0.398 is a gap of 0.26 %), else of the optimum, else
100·f where f* = 0; every table says which (:func:`gap_measure`) and shows f and f* beside it.
"""

from __future__ import annotations

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.ground_truth import GroundTruth
from mechopt.optimize.problem import DesignProblem
from mechopt.studies.catalogue import Study

__all__ = ["declared_truth", "gap_basis", "gap_measure", "gap_pct", "known_truth", "tolerance"]


def known_truth(problem: DesignProblem) -> GroundTruth | None:
    """The optimum a problem declares (``f_min``, ``x_min``: test functions, a synthesis against a known target)."""
    f_min = getattr(problem, "f_min", None)
    if f_min is None or not np.isfinite(f_min):
        return None
    x = np.atleast_2d(np.asarray(getattr(problem, "x_min", np.full((1, problem.dim), np.nan)), dtype=float))[0]
    return GroundTruth(x=x.tolist(), fun=float(f_min), grid_x=x.tolist(), grid_fun=float(f_min), step=0.0,
                       n_evaluated=0, n_feasible=0, wall_time_s=0.0, key="known")


def declared_truth(study: Study) -> GroundTruth | None:
    """The optimum a study file declares in ``[compare] known_optimum`` (a brute force recorded with the study),
    simulated here so that the score's reference is this engine's own value."""
    known = study.section("compare").get("known_optimum")
    if not isinstance(known, dict):
        return None
    problem = study.problem
    try:
        x = np.array([float(known[v]) for v in problem.names])
    except (KeyError, TypeError, ValueError):
        raise InputError(f"{study.name}: [compare] known_optimum must give {list(problem.names)}") from None
    fun = float(problem.evaluate(x)[problem.objective])
    return GroundTruth(x=x.tolist(), fun=fun, grid_x=x.tolist(), grid_fun=fun, step=0.0, n_evaluated=0,
                       n_feasible=0, wall_time_s=0.0, key="declared")


def tolerance(problem: DesignProblem, truth: GroundTruth) -> float:
    """How close to the optimum counts as reaching it: 0.5 % of the function's range over the box where the problem
    declares it (test functions), 0.5 % of the optimum, or 1e-6 absolute where the optimum is 0."""
    f_range = _f_range(problem)
    if f_range is not None:
        return 0.005 * f_range
    return 0.005 * abs(truth.fun) if truth.fun else 1e-6


def gap_pct(problem: DesignProblem, truth: GroundTruth, value: float) -> float:
    """The gap in per cent: of the range over the box (test functions), of the optimum, or ×1e6 absolute at 0."""
    if not np.isfinite(value):
        return float("nan")
    f_range = _f_range(problem)
    if f_range is not None:
        return 100 * (value - truth.fun) / f_range
    return 100 * (value / truth.fun - 1) if truth.fun else 100 * value


def _f_range(problem: DesignProblem) -> float | None:
    f_range = getattr(problem, "f_range", None)
    return float(f_range) if f_range is not None and np.isfinite(f_range) and f_range > 0 else None


def gap_measure(problem: DesignProblem, truth: GroundTruth) -> str:
    """What the gap of :func:`gap_pct` is a percentage of, in words for a table's header."""
    obj = problem.objective
    f_range = _f_range(problem)
    if f_range is not None:
        return f"% of the range of {obj} over the box ({f_range:.4g}): 100 ({obj} - {obj}*) / range"
    if truth.fun:
        return f"% of {obj}*: 100 ({obj} / {obj}* - 1)"
    return f"100 ({obj} - {obj}*), {obj}* = 0"


def gap_basis(problem: DesignProblem, truth: GroundTruth) -> str:
    """The gap's unit in a few words, for a column header (:func:`gap_measure` says it in full)."""
    obj = problem.objective
    if _f_range(problem) is not None:
        return f"% of the range of {obj}"
    return f"% of {obj}*" if truth.fun else f"100 {obj}, {obj}* = 0"
