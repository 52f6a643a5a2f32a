"""A robust optimum: the design whose scatter (by the variables' tolerances) has the least mean (or quantile) of
the objective, each margin violated with probability at most a target.

The margins are exact, so each probability is a Monte Carlo estimate over a fixed scatter (common random numbers:
a scrambled Sobol set); the constraint is written on the margin's quantile at a level a little below the target
(:func:`safe_level`), which is continuous in the design, so SLSQP can step on it.  The objective is a local
Gaussian process fitted to the designs already simulated near the candidate; each round simulates the candidate
and a design one tolerance along each variable from it, refits, and solves again, within a budget of simulations.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import minimize as scipy_minimize

from mechopt.optimize.analysis.objective_model import fit_objective_model, stored_designs
from mechopt.optimize.analysis.scatter import Tolerances
from mechopt.optimize.analysis.scatter_statistics import ScatterStatistics, scatter_statistics
from mechopt.optimize.problem import DesignProblem

__all__ = ["RobustOptimum", "robust_optimum", "safe_level"]

#: Margins of designs that cannot be assembled are -inf; the quantile needs finite values.
_FLOOR = -1e6
#: The search stops when a round moves the design by less than this many tolerances in every variable: the
#: scatter's statistics then change by a small part of their spread.
CONVERGED = 0.25


@dataclass(frozen=True)
class RobustOptimum:
    """A robust optimum beside the nominal one.

    Attributes
    ----------
    x, nominal_x : (d,) ndarray
        The robust and the nominal optimum, in the variables' units.
    fun, nominal_fun : float
        Their simulated objective (the nominal designs themselves, not scattered).
    robust, nominal : ScatterStatistics
        The scatter's statistics of each (violation probabilities, the objective's mean and quantiles).
    price : float
        Relative rise of the simulated objective, ``fun / nominal_fun - 1``.
    simulations : int
        Simulations beyond the nominal run.
    max_violation : float
        The target probability.
    message : str
        How the search ended.
    """

    x: np.ndarray
    fun: float
    nominal_x: np.ndarray
    nominal_fun: float
    robust: ScatterStatistics
    nominal: ScatterStatistics
    price: float
    simulations: int
    max_violation: float
    message: str

    def lines(self, problem: DesignProblem) -> list[str]:
        """The robust and the nominal optimum side by side."""
        unit = problem.output_units.get(problem.objective, "")
        out = [f"robust optimum {problem.describe(self.x)}: {problem.objective} {self.fun:.6g} {unit} "
               f"(+{100 * self.price:.2f} % over the nominal), P(any margin violated) "
               f"{self.robust.violation['any']:.4f}, scatter mean {self.robust.mean:.6g}",
               f"nominal optimum {problem.describe(self.nominal_x)}: {problem.objective} {self.nominal_fun:.6g} "
               f"{unit}, P(any margin violated) {self.nominal.violation['any']:.4f}, scatter mean "
               f"{self.nominal.mean:.6g}",
               f"{self.simulations} simulations beyond the nominal run; {self.message}"]
        return out

    def to_dict(self, problem: DesignProblem) -> dict[str, Any]:
        """JSON-able summary."""
        def stats(s: ScatterStatistics) -> dict[str, Any]:
            return {"violation": s.violation, "mean": s.mean,
                    "quantiles": {f"{k:g}": v for k, v in s.quantiles.items()}}

        return {"x": dict(zip(problem.names, map(float, self.x), strict=True)), "fun": self.fun,
                "nominal_x": dict(zip(problem.names, map(float, self.nominal_x), strict=True)),
                "nominal_fun": self.nominal_fun, "robust": stats(self.robust), "nominal": stats(self.nominal),
                "price": self.price, "simulations": self.simulations, "max_violation": self.max_violation,
                "message": self.message}


def safe_level(target: float, n: int) -> float:
    """The quantile level p whose estimate over n designs stays below ``target`` by two binomial standard errors:
    p + 2 sqrt(p (1 - p) / n) = target."""
    lo, hi = 0.0, target
    for _ in range(60):
        p = 0.5 * (lo + hi)
        lo, hi = (p, hi) if p + 2.0 * math.sqrt(p * (1.0 - p) / n) < target else (lo, p)
    return max(lo, 0.5 / n)


def _solve(problem: DesignProblem, predict: Callable[[np.ndarray], np.ndarray], D: np.ndarray, start: np.ndarray,
           level: float, statistic: str | float) -> np.ndarray:
    """The robust design on the model: SLSQP on the scatter's statistic, each margin's ``level`` quantile >= 0."""
    b = problem.bounds
    w = b[:, 1] - b[:, 0]

    def design(u: np.ndarray) -> np.ndarray:
        return b[:, 0] + u * w

    def objective(u: np.ndarray) -> float:
        v = predict(design(u) + D)
        return float(v.mean() if statistic == "mean" else np.quantile(v, float(statistic)))

    def margins(u: np.ndarray) -> np.ndarray:
        M = np.maximum(problem.constraint_margins(design(u) + D), _FLOOR)
        return np.quantile(M, level, axis=0)

    scale = abs(objective((start - b[:, 0]) / w)) or 1.0
    cons = [{"type": "ineq", "fun": margins}] if problem.constraints else []
    res = scipy_minimize(lambda u: objective(u) / scale, (start - b[:, 0]) / w, method="SLSQP",
                         bounds=[(0.0, 1.0)] * problem.dim, constraints=cons,
                         options={"maxiter": 200, "ftol": 1e-12, "eps": 1e-7})
    u = np.clip(res.x, 0.0, 1.0)
    return design(u) if not problem.constraints or np.all(margins(u) >= -1e-9) else start


def robust_optimum(problem: DesignProblem, sampler: Any, nominal_x: np.ndarray, tolerances: Tolerances,
                   max_violation: float, budget: int = 30, nearest: int = 80,
                   log: Callable[[str], None] = lambda _line: None) -> RobustOptimum:
    """Search the robust optimum from the nominal one, on models refitted as simulations come in.

    Parameters
    ----------
    problem : DesignProblem
        The problem.
    sampler : Sampler
        Simulates through the run's store (its designs build the models).
    nominal_x : (d,) ndarray
        The nominal optimum, in the variables' units.
    tolerances : Tolerances
        The scatter and the statistic minimised.
    max_violation : float
        Target probability that each margin is violated, in (0, 0.5).
    budget : int
        Most simulations beyond the nominal run (each round costs d + 1).
    nearest : int
        Stored designs each local model is fitted to.
    log : callable
        Progress lines.
    """
    t = tolerances.vector(problem)
    D = tolerances.deviations(problem)
    level = safe_level(max_violation, D.shape[0])
    before = sampler.n_computed
    x = np.asarray(nominal_x, dtype=float)
    message = f"budget of {budget} simulations spent"
    for rnd in range(max(budget // (problem.dim + 1), 1)):
        X, y = stored_designs(problem, sampler.store)
        model = fit_objective_model(problem, X, y, centre=x, nearest=nearest, seed=rnd)
        new = _solve(problem, model.predict, D, x, level, tolerances.statistic)
        moved = np.abs(new - x) / t.clip(min=1e-12)
        log(f"  robust round {rnd + 1}: {problem.describe(new)} (moved {moved.max():.3g} tolerances)")
        if rnd and moved.max() < CONVERGED:
            message = f"converged after {rnd + 1} rounds (the last moved {moved.max():.2g} tolerances)"
            x = new
            break
        x = new
        if sampler.n_computed - before + problem.dim + 1 > budget:
            break
        step = np.where(t > 0, t, 0.0)
        probes = np.vstack([x, x + np.diag(step)[t > 0]])
        sampler(probes, desc="robust optimum")
    X, y = stored_designs(problem, sampler.store)
    final = fit_objective_model(problem, X, y, centre=x, nearest=nearest, seed=0)
    check = tolerances.deviations(problem, seed=tolerances.seed + 1)  # an independent scatter for the report
    fun, nominal_fun = (float(v) for v in sampler(np.vstack([x, nominal_x]), desc="robust optimum"))
    nominal_model = fit_objective_model(problem, X, y, centre=nominal_x, nearest=nearest, seed=0)
    return RobustOptimum(x=x, fun=fun, nominal_x=np.asarray(nominal_x, dtype=float), nominal_fun=nominal_fun,
                         robust=scatter_statistics(problem, final.predict, x, check),
                         nominal=scatter_statistics(problem, nominal_model.predict, nominal_x, check),
                         price=fun / nominal_fun - 1.0, simulations=sampler.n_computed - before,
                         max_violation=max_violation, message=message)
