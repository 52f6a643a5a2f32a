"""Heuristic and classical optimizers of the literature, as budget-limited baselines for mechopt's surrogate.

Every baseline has the signature ``minimize_<name>(problem: CountedProblem, seed: int, **options) ->
OptimizeResult`` and returns the best *feasible* design it simulated (``x``, ``fun``) with the number of simulator
calls used (``nfev <= problem.budget``); :class:`~mechopt.optimize.budget.CountedProblem` enforces the budget.

:data:`BASELINES` holds the in-house implementations (:data:`IN_HOUSE_BASELINES`) and wrappers of maintained optimizer
libraries (:data:`LIBRARY_BASELINES`: Optuna, SMT, pymoo, nevergrad).  The libraries are the optional ``compare``
extra, imported only when their baseline runs; a missing one raises
:class:`~optimize.baselines.library.MissingLibraryError` with a one-line message.
"""

from __future__ import annotations

from collections.abc import Callable

from scipy.optimize import OptimizeResult

from mechopt.optimize.baselines.bayesian import minimize_bayesian
from mechopt.optimize.baselines.differential_evolution import minimize_differential_evolution
from mechopt.optimize.baselines.dual_annealing import minimize_dual_annealing
from mechopt.optimize.baselines.library import MissingLibraryError
from mechopt.optimize.baselines.nelder_mead import minimize_nelder_mead
from mechopt.optimize.baselines.nevergrad_optimizers import minimize_nevergrad_cma, minimize_nevergrad_ngopt
from mechopt.optimize.baselines.optuna_samplers import minimize_optuna_cmaes, minimize_optuna_tpe
from mechopt.optimize.baselines.paper000_hybrid import minimize_paper000_hybrid
from mechopt.optimize.baselines.powell_penalty import minimize_powell_penalty
from mechopt.optimize.baselines.pymoo_algorithms import minimize_pymoo_de, minimize_pymoo_ga, minimize_pymoo_pso
from mechopt.optimize.baselines.sce_ua import minimize_sce_ua
from mechopt.optimize.baselines.slsqp import minimize_slsqp
from mechopt.optimize.baselines.smt_ego import minimize_smt_ego
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = [
    "BASELINES",
    "BASELINE_DOCS",
    "BudgetExhausted",
    "CountedProblem",
    "IN_HOUSE_BASELINES",
    "LIBRARY_BASELINES",
    "MissingLibraryError",
    "minimize_bayesian",
    "minimize_differential_evolution",
    "minimize_dual_annealing",
    "minimize_nelder_mead",
    "minimize_nevergrad_cma",
    "minimize_nevergrad_ngopt",
    "minimize_optuna_cmaes",
    "minimize_optuna_tpe",
    "minimize_paper000_hybrid",
    "minimize_powell_penalty",
    "minimize_pymoo_de",
    "minimize_pymoo_ga",
    "minimize_pymoo_pso",
    "minimize_sce_ua",
    "minimize_slsqp",
    "minimize_smt_ego",
]

#: In-house implementations: short name -> baseline ``f(problem, seed, **options) -> OptimizeResult``.
IN_HOUSE_BASELINES: dict[str, Callable[..., OptimizeResult]] = {
    "differential_evolution": minimize_differential_evolution,
    "dual_annealing": minimize_dual_annealing,
    "nelder_mead": minimize_nelder_mead,
    "slsqp": minimize_slsqp,
    "powell_penalty": minimize_powell_penalty,
    "paper000_hybrid": minimize_paper000_hybrid,
    "sce_ua": minimize_sce_ua,
    "bayesian": minimize_bayesian,
}

#: Maintained libraries (the optional ``compare`` extra), same signature and budget accounting.
LIBRARY_BASELINES: dict[str, Callable[..., OptimizeResult]] = {
    "optuna_tpe": minimize_optuna_tpe,
    "optuna_cmaes": minimize_optuna_cmaes,
    "smt_ego": minimize_smt_ego,
    "pymoo_ga": minimize_pymoo_ga,
    "pymoo_pso": minimize_pymoo_pso,
    "pymoo_de": minimize_pymoo_de,
    "nevergrad_ngopt": minimize_nevergrad_ngopt,
    "nevergrad_cma": minimize_nevergrad_cma,
}

#: Short name -> baseline with the common signature ``f(problem, seed, **options) -> OptimizeResult``.
BASELINES: dict[str, Callable[..., OptimizeResult]] = {**IN_HOUSE_BASELINES, **LIBRARY_BASELINES}

#: Short name -> one-line description with the reference and the constraint scheme.
BASELINE_DOCS: dict[str, str] = {
    "differential_evolution": "scipy differential evolution, best1bin (Storn & Price 1997); constraints by "
    "Lampinen's feasibility rules, infeasible trials never simulated.",
    "dual_annealing": "scipy generalised simulated annealing with L-BFGS-B local search (Xiang et al. 1997); "
    "rejection, infeasible visits never simulated.",
    "nelder_mead": "multistart Nelder-Mead simplex (Nelder & Mead 1965) from feasible Latin-hypercube starts, "
    "budget split; rejection.",
    "slsqp": "multistart SLSQP (Kraft 1988), constraints as inequality constraints, counted forward-difference "
    "gradients (the SQP route of paper 003).",
    "powell_penalty": "Powell's conjugate directions (Powell 1964) with Box's sin² bound transform and a "
    "sequence of quadratic exterior penalties (paper 001).",
    "paper000_hybrid": "paper 000's hybrid: GA on the dimensions (feasible initial population, SBX, polynomial "
    "mutation, 5 % elitism; λ = 50 quadratic penalty, infeasible children not simulated), then SLSQP from its 100 "
    "best distinct designs.",
    "sce_ua": "shuffled complex evolution (Duan, Sorooshian & Gupta 1992), best of paper 004; feasible-space "
    "rejection with random resampling.",
    "bayesian": "Bayesian optimisation, Matérn-5/2 GP with ML-II hyperparameters and expected improvement "
    "(Jones, Schonlau & Welch 1998); infeasible candidates rejected before simulation.",
    "optuna_tpe": "Optuna's multivariate TPE (Bergstra et al. 2011), ask/tell; Optuna's constrained TPE "
    "(trial.set_constraint), infeasible trials told as pruned, never simulated.",
    "optuna_cmaes": "Optuna's CMA-ES sampler (Hansen & Ostermeier 2001), ask/tell; it ignores constraints: "
    "infeasible trials not simulated, told a penalty above every simulated value.",
    "smt_ego": "SMT's EGO, Matérn-5/2 Kriging + expected improvement (Jones et al. 1998); infill maximises EI "
    "under the margins (SLSQP), only feasible designs simulated.",
    "pymoo_ga": "pymoo GA, SBX + polynomial mutation, elitist survival (Deb 2001); feasibility-first tournament "
    "and survival (Deb 2000), infeasible designs not simulated.",
    "pymoo_pso": "pymoo adaptive PSO (Zhan et al. 2009); feasibility-first personal/global bests, infeasible "
    "designs not simulated.",
    "pymoo_de": "pymoo DE/best/1/bin, F 0.5, CR 0.9 (Storn & Price 1997); feasibility-first replacement, "
    "infeasible designs not simulated.",
    "nevergrad_ngopt": "nevergrad's recommended NGOpt wizard (COBYLA at 3 variables and <= 150 calls); "
    "nevergrad's cheap-constraint resampling, leftovers penalised, not simulated.",
    "nevergrad_cma": "nevergrad's CMA-ES (pycma); nevergrad's cheap-constraint resampling, leftovers penalised, "
    "not simulated.",
}
