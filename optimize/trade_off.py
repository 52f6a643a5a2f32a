"""The default method on a problem with several objectives or limits on simulated outputs, through the sample store.

:func:`run_trade_off` is what :func:`mechopt.minimize` runs for ``method="auto"`` when the problem is a trade-off
(:attr:`~mechopt.optimize.problem.DesignProblem.trade_off`): every output the objectives and limits name is read from
the store's records, the search is :func:`~mechopt.optimize.auto.multi_objective.trade_off_search`, and the answer
:func:`~mechopt.optimize.trade_off_answer.trade_off_answer`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.auto.multi_objective import trade_off_search
from mechopt.optimize.problem import DesignProblem
from mechopt.optimize.result import OptimizeResult
from mechopt.optimize.trade_off_answer import declared_scale, trade_off_answer
from mechopt.runs.store import design_key

__all__ = ["check_trade_off_method", "run_trade_off"]


def check_trade_off_method(problem: DesignProblem, method: object) -> None:
    """Refuse, in one line, a method other than ``"auto"`` on several objectives or limits on simulated outputs."""
    from mechopt.optimize.methods import get_method

    if not problem.trade_off or get_method(method).max_objectives > 1:
        return
    spec, limits = problem.objective_spec, problem.limit_spec
    what = f"{spec.k} objectives" if spec.k > 1 else f"limits on simulated outputs ({limits.describe()})"
    name = method if isinstance(method, str) else getattr(method, "__name__", "custom")
    raise InputError(f"method {name!r} takes one objective and no limits on simulated outputs, got {what}; "
                     "expected method 'auto'")


class _MissingOutputWatch:
    """A sampler's watcher: the one-line error of a missing named output, at the first design that lacks it."""

    def __init__(self, problem: DesignProblem) -> None:
        self.problem = problem

    def record(self, record: Any, cached: bool = False) -> None:
        _missing_output(self.problem, [record])


def _missing_output(problem: DesignProblem, records: list) -> None:
    """A one-line error when the simulator returned no output an objective or a limit names (the record stays in the
    store, failed, so nothing simulated is lost)."""
    named = [(n, "objective") for n in problem.objective_spec.names] + [(n, "limit") for n in problem.limit_spec.names]
    for r in records:
        if r.status != "failed" or not r.error:
            continue
        for name, role in named:
            if f"returned no output {name!r}" in r.error:
                raise InputError(f"problem {problem.name!r}: the {role} names output {name!r}, which the simulator "
                                 f"did not return at the first design ({problem.describe(r.design)}); expected it "
                                 f"among its outputs ({r.error})")


def run_trade_off(problem: DesignProblem, budget: int, seed: int, sampler, initial: np.ndarray | None = None,
                  desc: str = "auto", scalarise: bool = False) -> OptimizeResult:
    """Run the default method on a trade-off problem within ``budget`` simulations.

    Parameters
    ----------
    problem : DesignProblem
        A problem with several objectives, or limits, or both.
    budget : int
        Simulations to spend (``initial`` included).
    seed : int
        Seed of every random choice.
    sampler : Sampler
        The door to the simulator and the store (:class:`~mechopt.optimize.sparse.sampler.Sampler`).
    initial : (p, d) ndarray, optional
        Designs simulated first.
    desc : str
        Progress label.
    scalarise : bool
        Several objectives by ParEGO's scalarisations instead of the expected hypervolume improvement.

    Returns
    -------
    OptimizeResult
        The fields of :func:`~mechopt.optimize.trade_off_answer.trade_off_answer`, ``nfev`` and ``method``.

    Raises
    ------
    InputError
        The simulator returned no output an objective or a limit names (checked at the first simulation).
    """
    spec, limits = problem.objective_spec, problem.limit_spec
    outputs: list = []

    def evaluate(X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        records = sampler.records(X, desc=desc)
        F = np.array([spec.values(r.outputs) if r.ok else np.full(spec.k, np.nan) for r in records])
        G = np.array([limits.values(r.outputs) if r.ok else np.full(limits.m, np.nan) for r in records])
        G = G.reshape(len(records), limits.m)
        for r, f in zip(records, F, strict=True):
            outputs.append(dict(r.outputs) if r.ok else None)
            sampler.history[design_key(tuple(r.design))] = (tuple(r.design), float(f[0]))
        return F, G, np.array([r.ok for r in records], dtype=bool)

    def margins(X: np.ndarray) -> np.ndarray:
        return problem.constraint_margins(np.atleast_2d(X))

    watch = _MissingOutputWatch(problem)
    sampler.watchers.append(watch)  # at the first design that lacks one, before a broken-simulator stop
    try:
        run = trade_off_search(evaluate, problem.bounds, budget, spec.k, limits.lower, limits.upper, seed=seed,
                               feasible=problem.feasible, batch=sampler.batch_size,
                               margins=margins if problem.constraints else None, initial=initial,
                               scalarise=scalarise, declared=declared_scale(problem))
    finally:
        sampler.watchers.remove(watch)
    answer = trade_off_answer(problem, run.X, run.F, run.G, run.ok, outputs)
    acquisition = "ParEGO" if scalarise else "expected hypervolume improvement"
    kind = f"{acquisition} on {spec.k} objectives" if spec.k > 1 else "constrained expected improvement"
    limited = f" under limits {limits.describe()}" if limits.m else ""
    answer["message"] = f"{kind}{limited}, {run.X.shape[0]} simulations: {answer['message']}"
    return OptimizeResult(**answer, nfev=len(sampler.designs), method="auto", plan="trade-off", model=None,
                          stages=[], validation=None)
