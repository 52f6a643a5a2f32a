"""Sobol sensitivity indices of the objective: how much of its variance over a region each variable explains, alone
(first order) and with every interaction (total), from the model of the objective (``scipy.stats.sobol_indices``,
Saltelli 2010).

The variables are independent and uniform over ``region`` (a box, in the variables' units); by default the
bounding box of the problem's feasible designs.  Where the region holds infeasible designs the model's continuation
is used there (the model is fitted to the designs that could be simulated); the share of infeasible designs is
reported beside the indices.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.analysis.objective_model import fit_objective_model, stored_designs
from mechopt.optimize.problem import DesignProblem
from mechopt.runs.store import SampleStore

__all__ = ["Sensitivity", "sobol", "sensitivity"]


@dataclass(frozen=True)
class Sensitivity:
    """Sobol indices of the objective.

    Attributes
    ----------
    names : tuple of str
        The variables.
    first_order, total_order : (d,) ndarray
        The indices (fractions of the variance), in the variables' order.
    region : (d, 2) ndarray
        The box the variables are uniform over.
    infeasible_share : float
        Share of the region's designs that violate a margin.
    model_designs : int
        Simulated designs the model was fitted to.
    simulations : int
        New simulations this analysis ran.
    """

    names: tuple[str, ...]
    first_order: np.ndarray
    total_order: np.ndarray
    region: np.ndarray
    infeasible_share: float = 0.0
    model_designs: int = 0
    simulations: int = 0

    def lines(self) -> list[str]:
        """The indices, one variable a line."""
        box = ", ".join(f"{n} [{lo:g}, {hi:g}]" for n, (lo, hi) in zip(self.names, self.region, strict=True))
        out = [f"Sobol indices over {box} ({100 * self.infeasible_share:.0f} % of it infeasible; "
               f"model of {self.model_designs} designs)"]
        out += [f"  {n:>8s}: first order {f:.3f}, total {t:.3f}"
                for n, f, t in zip(self.names, self.first_order, self.total_order, strict=True)]
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-able summary."""
        return {"first_order": dict(zip(self.names, map(float, self.first_order), strict=True)),
                "total_order": dict(zip(self.names, map(float, self.total_order), strict=True)),
                "region": {n: list(map(float, r)) for n, r in zip(self.names, self.region, strict=True)},
                "infeasible_share": self.infeasible_share, "model_designs": self.model_designs,
                "simulations": self.simulations}


def sobol(func: Callable[[np.ndarray], np.ndarray], region: np.ndarray, n: int = 2**13,
          seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """First and total Sobol indices (d,) of ``func`` (m, d) -> (m,) with independent uniform variables on
    ``region`` (d, 2), by ``scipy.stats.sobol_indices`` with ``n`` base designs (a power of two)."""
    from scipy.stats import sobol_indices, uniform

    region = np.asarray(region, dtype=float)
    dists = [uniform(loc=lo, scale=hi - lo) for lo, hi in region]
    res = sobol_indices(func=lambda X: np.asarray(func(X.T), dtype=float)[None, :], n=n, dists=dists,
                        rng=np.random.default_rng(seed))
    return np.asarray(res.first_order, dtype=float).ravel(), np.asarray(res.total_order, dtype=float).ravel()


def _region(problem: DesignProblem, region: Any) -> np.ndarray:
    """The box of the analysis: checked inside the bounds, or the bounding box of the feasible designs."""
    if region is None:
        from scipy.stats import qmc

        b = problem.bounds
        X = b[:, 0] + qmc.Sobol(problem.dim, seed=0).random(2**12) * (b[:, 1] - b[:, 0])
        F = X[problem.feasible(X)]
        return np.column_stack([F.min(axis=0), F.max(axis=0)]) if F.shape[0] > 1 else b
    if isinstance(region, dict):
        unknown = sorted(set(region) - set(problem.names))
        if unknown:
            raise InputError(f"region for unknown variable {unknown[0]!r}; expected one of {list(problem.names)}")
        region = [region.get(v.name, (v.lower, v.upper)) for v in problem.variables]
    r = np.asarray(region, dtype=float)
    b = problem.bounds
    if r.shape != b.shape or not np.all(np.isfinite(r)) or np.any(r[:, 0] >= r[:, 1]) \
            or np.any(r[:, 0] < b[:, 0]) or np.any(r[:, 1] > b[:, 1]):
        raise InputError(f"region = {region!r}: expected a (lower, upper) pair per variable inside the bounds "
                         f"{b.tolist()}")
    return r


def sensitivity(problem: DesignProblem, *, store: str | Path | SampleStore | None = None, region: Any = None,
                simulations: int = 40, n: int = 2**13, seed: int = 0) -> Sensitivity:
    """Sobol indices of the objective over ``region``, from a model fitted to the store's designs.

    Parameters
    ----------
    problem : DesignProblem
        The problem.
    store : path or SampleStore, optional
        A run's sample store; its designs inside ``region`` build a global model of the objective.
    region : (d, 2) array_like or dict, optional
        The box (variables' units) or ``{name: (lower, upper)}``; default the bounding box of the feasible designs.
    simulations : int
        Most new simulations, spent when the store holds fewer than 10 d designs in the region: feasible designs of
        a Halton set over it.
    n : int
        Base designs of the Saltelli estimator (a power of two; (d + 2) n evaluations of the model).
    seed : int
        Seed of the estimator and of the model's fit.

    Raises
    ------
    InputError
        A bad region, or too few designs with the simulations allowed: before any simulation.
    """
    from mechopt.optimize.analysis.tolerance import local_sampler

    r = _region(problem, region)
    with local_sampler(problem, store) as sampler:
        X, y = stored_designs(problem, sampler.store)
        inside = np.all((X >= r[:, 0]) & (X <= r[:, 1]), axis=1) if X.size else np.zeros(0, bool)
        need = max(0, 10 * problem.dim - int(inside.sum()))
        if need > simulations:
            raise InputError(f"simulations = {simulations}: the store holds {int(inside.sum())} designs in the region "
                             f"and the model needs {10 * problem.dim}; expected simulations >= {need}")
        if need:
            from scipy.stats import qmc

            H = r[:, 0] + qmc.Halton(problem.dim, seed=seed).random(64 * need) * (r[:, 1] - r[:, 0])
            sampler(H[problem.feasible(H)][:need], desc="sensitivity: designs")
            X, y = stored_designs(problem, sampler.store)
            inside = np.all((X >= r[:, 0]) & (X <= r[:, 1]), axis=1)
        model = fit_objective_model(problem, X[inside], y[inside], seed=seed)
        first, total = sobol(model.predict, r, n=n, seed=seed)
        U = r[:, 0] + np.random.default_rng(seed).random((4096, problem.dim)) * (r[:, 1] - r[:, 0])
        return Sensitivity(names=problem.names, first_order=first, total_order=total, region=r,
                           infeasible_share=float(1.0 - problem.feasible(U).mean()), model_designs=model.n,
                           simulations=sampler.n_computed)
