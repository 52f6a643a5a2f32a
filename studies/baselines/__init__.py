"""Heuristic and classical optimizers of the literature, as budget-limited baselines for mechopt's surrogate.

Every baseline has the signature ``minimize_<name>(problem: CountedProblem, seed: int, **options) ->
OptimizeResult`` and returns the best *feasible* design it simulated (``x``, ``fun``) with the number of simulator
calls used (``nfev <= problem.budget``); :class:`~studies.baselines.problem.CountedProblem` enforces the budget.
:func:`~studies.baselines.rbf_surrogate.fit_and_search_rbf` is the surrogate baseline fed with given samples; it is
not in :data:`BASELINES` because it does not choose its own samples.
"""

from __future__ import annotations

from collections.abc import Callable

from scipy.optimize import OptimizeResult

from .bayesian import minimize_bayesian
from .differential_evolution import minimize_differential_evolution
from .dual_annealing import minimize_dual_annealing
from .genetic import minimize_genetic
from .nelder_mead import minimize_nelder_mead
from .particle_swarm import minimize_particle_swarm
from .powell_penalty import minimize_powell_penalty
from .problem import BudgetExhausted, CountedProblem
from .rbf_surrogate import fit_and_search_rbf
from .sce_ua import minimize_sce_ua
from .slsqp import minimize_slsqp

__all__ = [
    "BASELINES",
    "BASELINE_DOCS",
    "BudgetExhausted",
    "CountedProblem",
    "fit_and_search_rbf",
    "minimize_bayesian",
    "minimize_differential_evolution",
    "minimize_dual_annealing",
    "minimize_genetic",
    "minimize_nelder_mead",
    "minimize_particle_swarm",
    "minimize_powell_penalty",
    "minimize_sce_ua",
    "minimize_slsqp",
]

#: Short name -> baseline with the common signature ``f(problem, seed, **options) -> OptimizeResult``.
BASELINES: dict[str, Callable[..., OptimizeResult]] = {
    "differential_evolution": minimize_differential_evolution,
    "dual_annealing": minimize_dual_annealing,
    "nelder_mead": minimize_nelder_mead,
    "slsqp": minimize_slsqp,
    "powell_penalty": minimize_powell_penalty,
    "genetic": minimize_genetic,
    "sce_ua": minimize_sce_ua,
    "particle_swarm": minimize_particle_swarm,
    "bayesian": minimize_bayesian,
}

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
    "genetic": "real-coded GA, tournament + SBX + polynomial mutation + elitism (Deb 2001), then multistart "
    "Nelder-Mead/SLSQP from its best designs (hybrid of paper 000); static quadratic penalty.",
    "sce_ua": "shuffled complex evolution (Duan, Sorooshian & Gupta 1992), best of paper 004; feasible-space "
    "rejection with random resampling.",
    "particle_swarm": "global-best PSO with inertia/constriction coefficients (Clerc & Kennedy 2002); "
    "feasibility-preserving rejection (Hu & Eberhart 2002).",
    "bayesian": "Bayesian optimisation, Matérn-5/2 GP with ML-II hyperparameters and expected improvement "
    "(Jones, Schonlau & Welch 1998); infeasible candidates rejected before simulation.",
}
