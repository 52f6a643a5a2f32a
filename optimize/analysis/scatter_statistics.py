"""Monte Carlo over a scattered design: each margin's probability of violation (exact margins) and the objective's
mean and quantiles (its model)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mechopt.optimize.problem import DesignProblem

__all__ = ["QUANTILES", "ScatterStatistics", "scatter_statistics", "violation_probabilities"]

#: Quantile levels of the objective every analysis reports.
QUANTILES = (0.05, 0.5, 0.95)


@dataclass(frozen=True)
class ScatterStatistics:
    """What a nominal design's scatter does.

    Attributes
    ----------
    violation : dict
        Probability that each constraint's margin is negative, by constraint name, and ``"any"`` for at least one.
    standard_error : dict
        Binomial standard error of each probability (a plain Monte Carlo bound; the scrambled Sobol set does better).
    outside_box : float
        Probability that the scattered design leaves the variables' bounds (information: the box is a region of
        nominal designs, not a constraint).
    mean : float
        The objective's mean over the scatter (its model).
    quantiles : dict
        The objective's quantiles by level (``QUANTILES``).
    values : ndarray
        The objective's model at every scattered design (for figures).
    margins : ndarray
        The margins (n, n_constraints) at every scattered design.
    """

    violation: dict[str, float]
    standard_error: dict[str, float]
    outside_box: float
    mean: float
    quantiles: dict[float, float]
    values: np.ndarray = field(repr=False)
    margins: np.ndarray = field(repr=False)


def violation_probabilities(problem: DesignProblem, X: np.ndarray) -> tuple[dict[str, float], dict[str, float],
                                                                              np.ndarray]:
    """Probability that each margin is negative over designs X (n, d), its standard error, and the margins."""
    M = problem.constraint_margins(X) if problem.constraints else np.zeros((X.shape[0], 0))
    bad = M < 0.0
    n = X.shape[0]
    p = {c: float(bad[:, j].mean()) for j, c in enumerate(problem.constraints)}
    p["any"] = float(bad.any(axis=1).mean()) if bad.shape[1] else 0.0
    se = {k: float(np.sqrt(max(v * (1.0 - v), 1.0 / n) / n)) for k, v in p.items()}
    return p, se, M


def scatter_statistics(problem: DesignProblem, predict, x: np.ndarray, deviations: np.ndarray) -> ScatterStatistics:
    """Statistics of nominal design ``x`` (d,) scattered by ``deviations`` (n, d), the objective by ``predict``.

    Parameters
    ----------
    problem : DesignProblem
        Its margins are evaluated exactly at every scattered design.
    predict : callable
        The objective's model, ``(n, d) -> (n,)``, in the objective's unit.
    x : (d,) ndarray
        The nominal design, in the variables' units.
    deviations : (n, d) ndarray
        The scatter (:meth:`mechopt.optimize.analysis.scatter.Tolerances.deviations`).
    """
    X = np.asarray(x, dtype=float)[None, :] + deviations
    p, se, M = violation_probabilities(problem, X)
    values = np.asarray(predict(X), dtype=float)
    q = np.quantile(values, QUANTILES)
    return ScatterStatistics(violation=p, standard_error=se, outside_box=float(np.mean(~problem.in_box(X))),
                             mean=float(values.mean()), quantiles=dict(zip(QUANTILES, map(float, q), strict=True)),
                             values=values, margins=M)
