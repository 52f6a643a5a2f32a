"""Peers for several objectives and limits: pymoo's NSGA-II, Optuna's TPE and GPSampler, BoTorch's qLogNEHVI.

Each peer spends exactly ``budget`` evaluations of a :class:`~mechopt.optimize.problem.DesignProblem` with several
objectives (and limits) and returns every design it evaluated with its minimised objectives and limited outputs,
as :class:`PeerRun`; the caller scores the front (:mod:`mechopt.optimize.pareto`).  The peers call the problem's
``evaluate`` directly (no sample store): they are for benchmarks on closed-form test problems.  A limit
``lower <= g <= upper`` is given to each library as its own constraint convention (pymoo: G <= 0; Optuna:
``constraints_func`` values <= 0; BoTorch: an outcome constraint on a modelled output).

pymoo and Optuna's TPE need the ``compare`` extra; GPSampler and BoTorch need PyTorch (the ``gp-peers`` extra).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from mechopt.optimize.problem import DesignProblem

__all__ = ["MULTI_OBJECTIVE_PEERS", "PeerRun", "botorch_qlognehvi", "nsga2", "optuna_gp", "optuna_tpe"]


@dataclass
class PeerRun:
    """Every design a peer evaluated, in order.

    Attributes
    ----------
    X : (n, d) ndarray
        Designs in the variables' units.
    F : (n, k) ndarray
        Minimised objectives.
    G : (n, m) ndarray
        Limited outputs.
    """

    X: list = field(default_factory=list)
    F: list = field(default_factory=list)
    G: list = field(default_factory=list)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(X, F, G) as arrays."""
        return np.array(self.X), np.array(self.F), np.array(self.G).reshape(len(self.X), -1)


class _Counted:
    """The problem's evaluator with the record of every call (minimised objectives, limited outputs, violations)."""

    def __init__(self, problem: DesignProblem) -> None:
        self.problem = problem
        self.spec, self.limits = problem.objective_spec, problem.limit_spec
        self.run = PeerRun()

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Minimised objectives (k,) and the constraint values (2m,) <= 0 where met, of one design."""
        x = np.asarray(x, dtype=float)
        out = self.problem.evaluate(x)
        f, g = self.spec.values(out), self.limits.values(out)
        self.run.X.append(x)
        self.run.F.append(f)
        self.run.G.append(g)
        return f, self.constraint_values(g)

    def constraint_values(self, g: np.ndarray) -> np.ndarray:
        """``lower - g`` and ``g - upper`` of every finite side (<= 0 where met)."""
        parts = [lo - v for v, lo in zip(g, self.limits.lower, strict=True) if math.isfinite(lo)]
        parts += [v - hi for v, hi in zip(g, self.limits.upper, strict=True) if math.isfinite(hi)]
        return np.array(parts, dtype=float)

    @property
    def n_constraints(self) -> int:
        return int(np.isfinite(self.limits.lower).sum() + np.isfinite(self.limits.upper).sum())


def nsga2(problem: DesignProblem, budget: int, seed: int) -> PeerRun:
    """pymoo's NSGA-II (Deb et al. 2002) with constraint domination; population max(10, budget / 10)."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize as pymoo_minimize

    counted = _Counted(problem)
    b = problem.bounds

    class _Wrapped(Problem):
        def __init__(self) -> None:
            super().__init__(n_var=problem.dim, n_obj=counted.spec.k, n_ieq_constr=counted.n_constraints,
                             xl=b[:, 0], xu=b[:, 1])

        def _evaluate(self, X, out, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003 - pymoo's signature
            rows = [counted(x) for x in X]
            out["F"] = np.array([r[0] for r in rows])
            if counted.n_constraints:
                out["G"] = np.array([r[1] for r in rows])

    pymoo_minimize(_Wrapped(), NSGA2(pop_size=max(10, budget // 10)), ("n_eval", budget), seed=seed, verbose=False)
    _trim(counted.run, budget)
    return counted.run


def _trim(run: PeerRun, budget: int) -> None:
    """Keep the first ``budget`` evaluations (a generation may overrun the budget)."""
    run.X, run.F, run.G = run.X[:budget], run.F[:budget], run.G[:budget]


def _optuna(problem: DesignProblem, budget: int, seed: int, make_sampler: Callable) -> PeerRun:
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    counted = _Counted(problem)
    names, b = problem.names, problem.bounds
    constraints = counted.n_constraints > 0

    def constraints_func(trial) -> list[float]:  # noqa: ANN001 - an Optuna FrozenTrial
        return list(trial.user_attrs["constraints"])

    sampler = make_sampler(seed, constraints_func if constraints else None)
    study = optuna.create_study(directions=["minimize"] * counted.spec.k, sampler=sampler)

    def objective(trial) -> tuple[float, ...]:  # noqa: ANN001 - an Optuna Trial
        x = np.array([trial.suggest_float(n, lo, hi) for n, (lo, hi) in zip(names, b, strict=True)])
        f, c = counted(x)
        trial.set_user_attr("constraints", [float(v) for v in c])
        return tuple(float(v) for v in f)

    study.optimize(objective, n_trials=budget)
    return counted.run


def optuna_tpe(problem: DesignProblem, budget: int, seed: int) -> PeerRun:
    """Optuna's TPE in its multi-objective mode (MOTPE), with ``constraints_func`` for limits."""
    import optuna

    return _optuna(problem, budget, seed,
                   lambda s, c: optuna.samplers.TPESampler(seed=s, constraints_func=c, multivariate=True))


def optuna_gp(problem: DesignProblem, budget: int, seed: int) -> PeerRun:
    """Optuna's GPSampler (log expected hypervolume improvement with several objectives), needs PyTorch."""
    import optuna

    from mechopt.optimize.baselines.torch_threads import one_torch_thread

    with one_torch_thread():
        return _optuna(problem, budget, seed, lambda s, c: optuna.samplers.GPSampler(
            seed=s, constraints_func=c, deterministic_objective=True))


def botorch_qlognehvi(problem: DesignProblem, budget: int, seed: int) -> PeerRun:
    """BoTorch's qLogNEHVI (Daulton et al. 2021; Ament et al. 2023), one GP per objective and per constraint, a
    Sobol start of 2(d + 1) designs, one design per step; needs PyTorch."""
    from mechopt.optimize.baselines.botorch_nehvi import run_qlognehvi

    counted = _Counted(problem)
    run_qlognehvi(counted, problem.bounds, budget, seed)
    return counted.run


#: Every peer by name.
MULTI_OBJECTIVE_PEERS: dict[str, Callable[[DesignProblem, int, int], PeerRun]] = {
    "pymoo_nsga2": nsga2, "optuna_tpe": optuna_tpe, "optuna_gp": optuna_gp, "botorch_qlognehvi": botorch_qlognehvi,
}
