"""pymoo's single-objective GA, PSO and DE as budget-limited baselines, with pymoo's own constraint handling.

Each algorithm runs through pymoo's ask/tell interface (``algorithm.setup(problem, seed=seed)``, ``ask``, evaluate,
``tell``) until :class:`CountedProblem` has spent the budget; the batch in progress when the budget runs out is cut
short (the problem keeps the best feasible design anyway).

Constraint handling: pymoo's feasibility-first rules (Deb 2000).  The pymoo problem declares the margins as
inequality constraints ``G = -margins <= 0`` plus one for the box excess; pymoo computes the constraint violation
``CV`` and ranks by ``CV`` first and the objective among feasible designs only (``comp_by_cv_and_fitness`` tournament
and ``FitnessSurvival`` for the GA, ``ImprovementReplacement`` for the DE trial vectors and the PSO personal bests,
least-infeasible optimum).  The objective of an infeasible design is never computed: it gets the rejection value of
:meth:`CountedProblem.penalised`, which pymoo's rules do not look at while the violation is positive.  A failed
simulation gets :attr:`CountedProblem.infeasible_value` (feasible, but worse than any simulated design).

Configurations (pymoo 0.6 names):

* ``pymoo_ga``: ``GA`` -- binary tournament by feasibility then fitness, ``SBX(eta=15, prob=0.9)``, ``PM(eta=20)``,
  ``FitnessSurvival`` (elitist (mu + lambda)), duplicate elimination; pymoo's defaults except the population.
* ``pymoo_pso``: ``PSO`` -- pymoo's adaptive PSO (Zhan et al. 2009: inertia and accelerations steered by the swarm's
  evolutionary state, perturbed global best), initial velocities random, ``max_velocity_rate=0.2``; pymoo's defaults
  except the swarm size.
* ``pymoo_de``: ``DE(variant="DE/best/1/bin", F=0.5, CR=0.9)`` -- pymoo's default variant (greedy, the right choice at
  small budgets) with Storn & Price's (1997) recommended ``CR = 0.9`` for non-separable problems instead of pymoo's
  0.2.

Every population starts from a Latin hypercube (``LHS``) in the box.  Population size: pymoo's defaults (100 for GA
and DE, 25 for PSO) would not finish two generations in 60 calls; the default here is ``clip(budget // 5, 8, 20)``
so that about five generations fit the budget, and 20 (the size of the in-house GA and PSO, and of paper 004) from
100 calls on.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.optimize.baselines.library import require
from mechopt.optimize.baselines.mixed_space import has_discrete
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["default_pop_size", "objective_value", "minimize_pymoo_de", "minimize_pymoo_ga", "minimize_pymoo_pso"]


def objective_value(problem: CountedProblem, x: np.ndarray) -> float:
    """The value pymoo is told for design ``x``: simulated when feasible (a failed simulation at the infeasible
    value), else the penalty, which counts the proposal but never simulates.  Raises BudgetExhausted when the
    budget is spent."""
    if problem.feasible(x)[0]:
        f = problem.evaluate(x)
        return f if math.isfinite(f) else problem.infeasible_value
    return problem.penalised(x)


def default_pop_size(budget: int) -> int:
    """Population of the pymoo baselines for a budget: about five generations, between 8 and 20 individuals.

    Parameters
    ----------
    budget : int
        Simulator calls.

    Returns
    -------
    int
    """
    return int(np.clip(budget // 5, 8, 20))


def _pymoo_problem(problem: CountedProblem) -> Any:
    """The counted problem as a pymoo ``Problem`` with ``m + 1`` inequality constraints (margins and box)."""
    core = require("pymoo.core.problem", "pymoo baselines")
    n_margins = problem.margins(0.5 * (problem.lower + problem.upper)).size

    class Counted(core.Problem):
        def __init__(self) -> None:
            super().__init__(n_var=problem.dim, n_obj=1, n_ieq_constr=n_margins + 1, xl=problem.lower.copy(),
                             xu=problem.upper.copy())

        def _evaluate(self, X: np.ndarray, out: dict, *args: Any, **kwargs: Any) -> None:
            F = np.empty((X.shape[0], 1))
            G = np.empty((X.shape[0], n_margins + 1))
            for i, x in enumerate(X):
                box = np.sum(np.maximum(problem.lower - x, 0.0)) + np.sum(np.maximum(x - problem.upper, 0.0))
                G[i, :n_margins] = -problem.margins(problem.clip(x))
                G[i, n_margins] = box
                F[i, 0] = objective_value(problem, x)
            out["F"] = F
            out["G"] = G

    return Counted()


def _run(problem: CountedProblem, seed: int, algorithm: Any, name: str) -> OptimizeResult:
    """pymoo ask/tell loop until the budget is spent."""
    pp = _pymoo_problem(problem)
    algorithm.setup(pp, termination=("n_gen", 10**9), seed=seed, verbose=False)
    n_gen = 0
    message = "budget spent"
    try:
        while problem.remaining > 0:
            pop = algorithm.ask()
            algorithm.evaluator.eval(pp, pop)
            algorithm.tell(infills=pop)
            n_gen += 1
    except BudgetExhausted as exc:
        message = str(exc)
    return problem.result(f"{name}: {message}", ngen=n_gen)


def minimize_pymoo_ga(
    problem: CountedProblem,
    seed: int,
    *,
    pop_size: int | None = None,
    eta_crossover: float = 15.0,
    p_crossover: float = 0.9,
    eta_mutation: float = 20.0,
) -> OptimizeResult:
    """pymoo's genetic algorithm (SBX, polynomial mutation, feasibility-first tournament), until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of pymoo's generator.
    pop_size : int, optional
        Individuals per generation, default :func:`default_pop_size`.
    eta_crossover, p_crossover : float
        SBX distribution index and probability (pymoo's defaults).
    eta_mutation : float
        Polynomial-mutation distribution index (pymoo's default).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``ngen`` (ask/tell
        rounds, the first being the initial population).

    Notes
    -----
    On a problem with discrete variables this is pymoo's ``MixedVariableGA``
    (:func:`~mechopt.optimize.baselines.pymoo_mixed_ga.minimize_pymoo_mixed_ga`, pymoo's own operators per kind of
    variable; the SBX and mutation options here do not apply).
    """
    if has_discrete(problem):
        # Imported here: that module reads default_pop_size of this one.
        from mechopt.optimize.baselines.pymoo_mixed_ga import minimize_pymoo_mixed_ga

        return minimize_pymoo_mixed_ga(problem, seed, pop_size=pop_size)
    ga = require("pymoo.algorithms.soo.nonconvex.ga", "pymoo_ga")
    sampling = require("pymoo.operators.sampling.lhs", "pymoo_ga")
    sbx = require("pymoo.operators.crossover.sbx", "pymoo_ga")
    pm = require("pymoo.operators.mutation.pm", "pymoo_ga")
    algorithm = ga.GA(pop_size=pop_size or default_pop_size(problem.budget), sampling=sampling.LHS(),
                      crossover=sbx.SBX(eta=eta_crossover, prob=p_crossover), mutation=pm.PM(eta=eta_mutation),
                      eliminate_duplicates=True)
    return _run(problem, seed, algorithm, "pymoo GA")


def minimize_pymoo_pso(
    problem: CountedProblem,
    seed: int,
    *,
    pop_size: int | None = None,
    adaptive: bool = True,
    max_velocity_rate: float = 0.2,
) -> OptimizeResult:
    """pymoo's adaptive particle swarm with feasibility-first personal and global bests, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of pymoo's generator.
    pop_size : int, optional
        Swarm size, default :func:`default_pop_size`.
    adaptive : bool, default True
        Zhan et al.'s adaptation of inertia and accelerations (pymoo's default).
    max_velocity_rate : float, default 0.2
        Velocity clamp as a fraction of the box width (pymoo's default).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``ngen``.
    """
    pso = require("pymoo.algorithms.soo.nonconvex.pso", "pymoo_pso")
    sampling = require("pymoo.operators.sampling.lhs", "pymoo_pso")
    algorithm = pso.PSO(pop_size=pop_size or default_pop_size(problem.budget), sampling=sampling.LHS(),
                        adaptive=adaptive, max_velocity_rate=max_velocity_rate)
    return _run(problem, seed, algorithm, "pymoo PSO")


def minimize_pymoo_de(
    problem: CountedProblem,
    seed: int,
    *,
    pop_size: int | None = None,
    variant: str = "DE/best/1/bin",
    F: float = 0.5,
    CR: float = 0.9,
) -> OptimizeResult:
    """pymoo's differential evolution with feasibility-first replacement, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of pymoo's generator.
    pop_size : int, optional
        Population, default :func:`default_pop_size`.
    variant : str, default "DE/best/1/bin"
        pymoo's ``DE/<selection>/<n_diffs>/<crossover>``.
    F : float, default 0.5
        Differential weight.
    CR : float, default 0.9
        Crossover probability.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``ngen``.
    """
    de = require("pymoo.algorithms.soo.nonconvex.de", "pymoo_de")
    sampling = require("pymoo.operators.sampling.lhs", "pymoo_de")
    algorithm = de.DE(pop_size=pop_size or default_pop_size(problem.budget), sampling=sampling.LHS(),
                      variant=variant, F=F, CR=CR)
    return _run(problem, seed, algorithm, "pymoo DE")
