"""Tolerance analysis of one design: the variables scattered by their tolerances, Monte Carlo on the exact margins
and on a model of the objective fitted to simulated designs, confirmed by a few simulations at the quantiles."""

from __future__ import annotations

import contextlib
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.analysis.objective_model import fit_objective_model, stored_designs
from mechopt.optimize.analysis.scatter import Tolerances, as_tolerances, check_design_in_box
from mechopt.optimize.analysis.scatter_statistics import QUANTILES, ScatterStatistics, scatter_statistics
from mechopt.optimize.problem import DesignProblem
from mechopt.runs.store import SampleStore

__all__ = ["ToleranceResult", "confirmation_designs", "local_sampler", "tolerance"]


@dataclass(frozen=True)
class ToleranceResult:
    """The tolerance analysis of a design.

    Attributes
    ----------
    design : (d,) ndarray
        The nominal design, in the variables' units.
    tolerances : Tolerances
        The tolerances applied.
    statistics : ScatterStatistics
        Violation probabilities, the objective's mean and quantiles (model refitted with the confirmations).
    confirmations : list of dict
        Each simulated design: ``level`` (quantile), ``design``, ``predicted`` (the model before it was simulated)
        and ``simulated`` (NaN when the simulation failed).
    simulations : int
        New simulations this analysis ran (designs found in the store cost none).
    model_designs : int
        Simulated designs the objective's model was fitted to.
    """

    design: np.ndarray
    tolerances: Tolerances
    statistics: ScatterStatistics
    confirmations: list[dict[str, Any]] = field(default_factory=list)
    simulations: int = 0
    model_designs: int = 0

    def lines(self, problem: DesignProblem) -> list[str]:
        """The analysis as lines of text with units."""
        s, unit = self.statistics, problem.output_units.get(problem.objective, "")
        out = [f"design {problem.describe(self.design)}; tolerances {self.tolerances.describe(problem)}; "
               f"{self.tolerances.samples} scattered designs"]
        for c in (*problem.constraints, "any"):
            out.append(f"  P(violated) {c:>20s}: {s.violation[c]:.4f} ± {s.standard_error[c]:.4f}")
        out.append(f"  P(outside the box): {s.outside_box:.4f}")
        q = ", ".join(f"{100 * k:g} %: {v:.6g}" for k, v in s.quantiles.items())
        out.append(f"  {problem.objective} ({unit}; model of {self.model_designs} designs): mean {s.mean:.6g}; {q}")
        for c in self.confirmations:
            out.append(f"  confirmed at the {100 * c['level']:g} % quantile: model {c['predicted']:.6g}, simulated "
                       f"{c['simulated']:.6g} ({problem.describe(c['design'])})")
        out.append(f"  new simulations: {self.simulations}")
        return out

    def to_dict(self, problem: DesignProblem) -> dict[str, Any]:
        """JSON-able summary."""
        s = self.statistics
        return {"design": dict(zip(problem.names, map(float, self.design), strict=True)),
                "tolerances": dict(self.tolerances.values), "distribution": self.tolerances.distribution,
                "samples": self.tolerances.samples, "violation": s.violation, "standard_error": s.standard_error,
                "outside_box": s.outside_box, "mean": s.mean,
                "quantiles": {f"{k:g}": v for k, v in s.quantiles.items()},
                "confirmations": [{"level": c["level"], "design": list(map(float, c["design"])),
                                   "predicted": c["predicted"], "simulated": c["simulated"]}
                                  for c in self.confirmations],
                "simulations": self.simulations, "model_designs": self.model_designs}


@contextlib.contextmanager
def local_sampler(problem: DesignProblem, store: str | Path | SampleStore | None):
    """A :class:`~mechopt.optimize.sparse.sampler.Sampler` on the caller's store (or a temporary one)."""
    from mechopt.optimize.sparse.sampler import Sampler
    from mechopt.runs.executors import make_executor

    with contextlib.ExitStack() as stack:
        if not isinstance(store, SampleStore):
            if store is None:
                store = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="mechopt-"))) / "samples.sqlite"
            store = stack.enter_context(SampleStore(store))
        yield Sampler(problem, store, stack.enter_context(make_executor(workers=1)), progress=False)


def confirmation_designs(values: np.ndarray, X: np.ndarray, k: int) -> list[tuple[float, np.ndarray]]:
    """``k`` scattered designs whose modelled objective is nearest to evenly spread quantiles (5/50/95 % first)."""
    levels = list(QUANTILES[:k]) if k <= len(QUANTILES) else list(np.linspace(0.05, 0.95, k))
    targets = np.quantile(values, levels)
    return [(float(lv), X[int(np.argmin(np.abs(values - t)))]) for lv, t in zip(levels, targets, strict=True)]


def tolerance(problem: DesignProblem, x: Any, tolerances: Any, *, store: str | Path | SampleStore | None = None,
              simulations: int = 10, nearest: int = 80, seed: int = 0) -> ToleranceResult:
    """Tolerance analysis of design ``x``: how often each margin fails, and how the objective spreads.

    Parameters
    ----------
    problem : DesignProblem
        The problem (its margins are exact and cheap; its evaluator is the simulator).
    x : (d,) array_like
        The nominal design, in the variables' units, inside the bounds.
    tolerances : Tolerances, mapping or float
        ± per variable in its unit (``{"oa": 0.1}``), one number for every variable, or a :class:`Tolerances`
        (distribution ``"uniform"`` by default, or ``"normal"`` with the tolerance as 3σ).
    store : path or SampleStore, optional
        The sample store of an earlier run: its designs build the objective's model.  Without enough designs near
        ``x`` (2d + 2 within 10 tolerances), a local Halton set is simulated first, within ``simulations``.
    simulations : int
        Most new simulations: the local set when needed, then designs at the objective's 5/50/95 % quantiles.
    nearest : int
        Stored designs nearest to ``x`` the model is fitted to.
    seed : int
        Seed of the model's fit (the scatter's is ``tolerances.seed``).

    Returns
    -------
    ToleranceResult

    Raises
    ------
    InputError
        An unknown variable, a negative tolerance or one larger than the range, a design outside the box, or a
        budget too small for the local set: before any simulation.
    """
    tol = as_tolerances(tolerances, problem)
    x = check_design_in_box(problem, x)
    if isinstance(simulations, bool) or not isinstance(simulations, int) or simulations < 0:
        raise InputError(f"simulations = {simulations!r}: expected a whole number >= 0")
    t = tol.vector(problem)
    with local_sampler(problem, store) as sampler:
        X, y = stored_designs(problem, sampler.store)
        near = int(np.sum(np.all(np.abs(X - x) <= 10.0 * np.maximum(t, 1e-12), axis=1))) if X.size else 0
        need = max(0, 2 * problem.dim + 2 - near)
        if need > simulations:
            raise InputError(f"simulations = {simulations}: the store holds {near} designs near the design, and the "
                             f"model of the objective needs {need} more there; expected simulations >= {need}")
        before = sampler.n_computed
        if need:
            from scipy.stats import qmc

            local = x + (2.0 * qmc.Halton(problem.dim, seed=seed).random(need) - 1.0) * 2.0 * t
            sampler(local, desc="tolerance: local designs")
            X, y = stored_designs(problem, sampler.store)
        deviations = tol.deviations(problem)
        model = fit_objective_model(problem, X, y, centre=x, nearest=nearest, seed=seed)
        stats = scatter_statistics(problem, model.predict, x, deviations)
        confirmations = []
        picks = confirmation_designs(stats.values, x + deviations, simulations - (sampler.n_computed - before))
        if picks:
            simulated = sampler(np.array([d for _, d in picks]), desc="tolerance: confirmations")
            confirmations = [{"level": lv, "design": d, "predicted": float(model.predict(d[None, :])[0]),
                              "simulated": float(v)} for (lv, d), v in zip(picks, simulated, strict=True)]
            X, y = stored_designs(problem, sampler.store)
            model = fit_objective_model(problem, X, y, centre=x, nearest=nearest, seed=seed)
            stats = scatter_statistics(problem, model.predict, x, deviations)
        return ToleranceResult(design=x, tolerances=tol, statistics=stats, confirmations=confirmations,
                               simulations=sampler.n_computed - before, model_designs=model.n)
