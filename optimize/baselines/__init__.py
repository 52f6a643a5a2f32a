"""Heuristic and classical optimizers of the literature, as budget-limited baselines for mechopt's surrogate.

Every baseline has the signature ``minimize_<name>(problem: CountedProblem, seed: int, **options) ->
OptimizeResult`` and returns the best *feasible* design it simulated (``x``, ``fun``) with the number of simulator
calls used (``nfev <= problem.budget``); :class:`~mechopt.optimize.budget.CountedProblem` enforces the budget.

The table of methods (:data:`mechopt.optimize.methods.METHODS`) names each baseline, with its summary.  Besides the
in-house implementations, some wrap maintained optimizer libraries (Optuna, SMT, pymoo, nevergrad, Py-BOBYQA): the
optional ``compare`` extra (BoTorch and Optuna's GPSampler: the ``gp-peers`` extra, with PyTorch), imported only when
their baseline runs; a missing one raises
:class:`~optimize.baselines.library.MissingLibraryError` with a one-line message.
"""

from __future__ import annotations

from mechopt.optimize.baselines.bayesian import minimize_bayesian
from mechopt.optimize.baselines.botorch_qlognei import minimize_botorch_qlognei
from mechopt.optimize.baselines.cobyqa import minimize_cobyqa
from mechopt.optimize.baselines.differential_evolution import minimize_differential_evolution
from mechopt.optimize.baselines.dual_annealing import minimize_dual_annealing
from mechopt.optimize.baselines.library import MissingLibraryError
from mechopt.optimize.baselines.nelder_mead import minimize_nelder_mead
from mechopt.optimize.baselines.nevergrad_optimizers import minimize_nevergrad_cma, minimize_nevergrad_ngopt
from mechopt.optimize.baselines.optuna_gp import minimize_optuna_gp
from mechopt.optimize.baselines.optuna_samplers import minimize_optuna_cmaes, minimize_optuna_tpe
from mechopt.optimize.baselines.paper000_hybrid import minimize_paper000_hybrid
from mechopt.optimize.baselines.powell_penalty import minimize_powell_penalty
from mechopt.optimize.baselines.py_bobyqa import minimize_py_bobyqa
from mechopt.optimize.baselines.pymoo_algorithms import minimize_pymoo_de, minimize_pymoo_ga, minimize_pymoo_pso
from mechopt.optimize.baselines.sce_ua import minimize_sce_ua
from mechopt.optimize.baselines.slsqp import minimize_slsqp
from mechopt.optimize.baselines.smt_ego import minimize_smt_ego
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = [
    "BudgetExhausted",
    "CountedProblem",
    "MissingLibraryError",
    "minimize_bayesian",
    "minimize_botorch_qlognei",
    "minimize_cobyqa",
    "minimize_differential_evolution",
    "minimize_dual_annealing",
    "minimize_nelder_mead",
    "minimize_nevergrad_cma",
    "minimize_nevergrad_ngopt",
    "minimize_optuna_cmaes",
    "minimize_optuna_gp",
    "minimize_optuna_tpe",
    "minimize_paper000_hybrid",
    "minimize_powell_penalty",
    "minimize_py_bobyqa",
    "minimize_pymoo_de",
    "minimize_pymoo_ga",
    "minimize_pymoo_pso",
    "minimize_sce_ua",
    "minimize_slsqp",
    "minimize_smt_ego",
]
