"""SMT's efficient global optimisation (EGO: Kriging + expected improvement), the nearest peer of mechopt's surrogate.

EGO (Jones, Schonlau & Welch 1998) as implemented by the Surrogate Modeling Toolbox (``smt.applications.EGO``, Bouhlel
et al. 2019; Saves et al. 2024).  Configuration:

* surrogate: ``KRG(corr="matern52", poly="constant", hyper_opt="TNC", n_start=10)`` -- ordinary Kriging with SMT's
  default hyperparameter fit (TNC, 10 starts) but the Matérn-5/2 kernel instead of SMT's default squared
  exponential: EGO packs samples near the optimum, where the squared exponential's correlation matrix becomes
  ill-conditioned, and Matérn-5/2 is the usual choice of the Bayesian-optimisation literature for a simulator output;
* criterion ``EI``, one point per iteration (``n_parallel=1``); the infill search evaluates EI on 1000 feasible
  random designs (and the incumbent) and runs SLSQP from the best 5 (``n_start=5``) -- better starts than SMT's
  default of 20 random LHS starts at a quarter of the cost (the SLSQP runs dominated an iteration's time);
* initial design: ``n_doe`` feasible Latin-hypercube designs, by default ``max(d + 1, min(10, budget // 4))`` (the
  rule of the in-house Bayesian baseline), then ``budget - n_doe`` EGO iterations -- SMT fixes the iteration count in
  advance, so it is set from the budget.  Kriging runs in the unit cube of the box.

Constraint handling: SMT's EGO has none.  Its infill step (``EGO._find_best_point``) is overridden by
:func:`_constrained_ego` to maximise the expected improvement *under the margins*: SLSQP from feasible starts with the
margins as inequality constraints (cheap, not counted), keeping only feasible optima; when none is feasible, the
feasible start of largest EI is taken.  So only feasible designs are ever simulated.  A proposal that repeats a
simulated design (EI collapsed on a sample: a second copy would make the Kriging matrix singular) is replaced by a
random feasible design.  A failed simulation enters the Kriging data at the worst value simulated so far.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult, minimize

from mechopt.optimize.baselines.library import kriging_values, require
from mechopt.optimize.baselines.mixed_space import has_discrete
from mechopt.optimize.baselines.smt_mixed_ego import minimize_smt_mixed_ego
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["EGO_MAX_BUDGETS", "max_budget", "minimize_smt_ego"]

#: The largest budget ``mechopt compare`` runs EGO at, as (most variables, budget): each step refits Kriging (a
#: hyperparameter search per variable) on every sample, a cost that grows with the cube of the simulations and with
#: the dimension; these are the budgets where a step still takes about 3 s of CPU on one BLAS thread
#: (benchmarks/bench_peer_budgets.py measures them; beyond 8 variables a step at 30 samples is not measured).
EGO_MAX_BUDGETS = ((3, 100), (5, 60), (12, 30))


def max_budget(dim: int) -> int:
    """The largest budget ``mechopt compare`` runs EGO at on ``dim`` variables (:data:`EGO_MAX_BUDGETS`)."""
    for most, budget in EGO_MAX_BUDGETS:
        if dim <= most:
            return budget
    return EGO_MAX_BUDGETS[-1][1]


def _constrained_ego(ego_class: type, problem: CountedProblem, rng: np.random.Generator, n_candidates: int) -> type:
    """Subclass of SMT's EGO whose infill maximises EI over the feasible region only (unit-cube coordinates)."""

    class ConstrainedEGO(ego_class):  # type: ignore[misc, valid-type]
        def _find_best_point(self, x_data=None, y_data=None, enable_tunneling=False):  # noqa: ANN001, ANN202
            self._train_gpr(x_data, y_data)
            d = problem.dim

            def neg_ei(u: np.ndarray) -> float:
                return -float(np.ravel(self.EI(np.atleast_2d(u), enable_tunneling, x_data))[0])

            # Starts of the infill search: the incumbent and the feasible random candidates of largest EI.
            cands = problem.to_unit(problem.sample_feasible(n_candidates, rng))
            incumbent = x_data[int(np.argmin(y_data[:, 0]))]
            cands = np.vstack([incumbent[None, :], cands])
            ei = np.ravel(self.EI(cands, enable_tunneling, x_data))
            starts = cands[np.argsort(-ei, kind="stable")[: self.options["n_start"]]]
            cons = []
            if problem.has_constraints:
                cons.append({"type": "ineq", "fun": lambda u: problem.margins(problem.from_unit(u))})
            best_u, best_val = None, math.inf
            for u0 in starts:
                value0 = neg_ei(u0)
                if value0 < best_val:
                    best_u, best_val = u0, value0
                res = minimize(neg_ei, u0, method="SLSQP", bounds=[(0.0, 1.0)] * d, constraints=cons,
                               options={"maxiter": 200})
                u = np.clip(res.x, 0.0, 1.0)
                if np.isfinite(res.fun) and res.fun < best_val and problem.feasible(problem.from_unit(u))[0]:
                    best_u, best_val = u, float(res.fun)
            if best_u is None or np.min(np.linalg.norm(x_data - best_u, axis=1)) < 1e-9:
                extra = problem.to_unit(problem.sample_feasible(1, rng))
                if extra.shape[0] == 0:
                    raise BudgetExhausted("no feasible design left to propose")
                best_u = extra[0]
            return np.atleast_2d(best_u), True

    return ConstrainedEGO


def minimize_smt_ego(
    problem: CountedProblem,
    seed: int,
    *,
    n_doe: int | None = None,
    n_start: int = 5,
    n_candidates: int = 1000,
    corr: str = "matern52",
    krg_options: dict[str, Any] | None = None,
) -> OptimizeResult:
    """SMT's EGO with Kriging and expected improvement maximised under the constraints, ``budget`` simulations.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the initial design, the infill starts and SMT's own draws (Kriging hyperparameter starts).
    n_doe : int, optional
        Feasible Latin-hypercube designs simulated first, default ``max(d + 1, min(10, budget // 4))``.
    n_start : int, default 5
        SLSQP starts of each infill search: the candidates of largest expected improvement.
    n_candidates : int, default 1000
        Feasible random designs on which the expected improvement is evaluated to choose the starts.
    corr : str, default "matern52"
        Kriging correlation kernel (see the module docstring).
    krg_options : dict, optional
        Further options of SMT's ``KRG``.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nit`` (EGO iterations
        asked of SMT).

    Notes
    -----
    On a problem with discrete variables this is SMT's mixed-integer EGO
    (:func:`~mechopt.optimize.baselines.smt_mixed_ego.minimize_smt_mixed_ego`: SMT's design space of integer and
    ordinal variables, its default squared-exponential kernel); ``corr`` does not apply there.
    """
    if has_discrete(problem):
        return minimize_smt_mixed_ego(problem, seed, n_doe=n_doe, n_start=n_start, n_candidates=n_candidates,
                                      krg_options=krg_options)
    applications = require("smt.applications", "smt_ego")
    models = require("smt.surrogate_models", "smt_ego")
    design_space = require("smt.design_space", "smt_ego")
    threadpoolctl = require("threadpoolctl", "smt_ego")
    rng = np.random.default_rng(seed)
    d = problem.dim
    n0 = max(d + 1, min(10, problem.budget // 4)) if n_doe is None else int(n_doe)
    n0 = min(n0, problem.budget)
    X0 = problem.sample_feasible(n0, rng)
    if X0.shape[0] == 0:
        return problem.result("no feasible initial design found", nit=0)
    n_iter = problem.budget - X0.shape[0]

    def fun(U: np.ndarray) -> np.ndarray:
        return kriging_values(problem, (problem.from_unit(u) for u in np.atleast_2d(U)))

    space = design_space.DesignSpace([design_space.FloatVariable(0.0, 1.0) for _ in range(d)], seed=seed)
    options = {"print_global": False, "corr": corr, "seed": seed, "design_space": space, **(krg_options or {})}
    surrogate = models.KRG(**options)
    ego = _constrained_ego(applications.EGO, problem, rng, n_candidates)(
        n_iter=n_iter, criterion="EI", xdoe=problem.to_unit(X0), surrogate=surrogate, n_start=n_start,
        seed=seed,
    )
    message = f"{n_iter} EGO iterations done"
    # The Kriging matrices are tiny: BLAS threads only fight each other (and other processes) over the cores, which
    # made a 12-point fit 30 times slower on a loaded 2-core machine.
    with threadpoolctl.threadpool_limits(limits=1):
        try:
            if n_iter > 0:
                ego.optimize(fun=fun)
            else:
                fun(problem.to_unit(X0))
        except BudgetExhausted as exc:
            message = str(exc)
    return problem.result(message, nit=n_iter)
