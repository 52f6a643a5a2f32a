"""Paper 000's hybrid optimizer: a genetic algorithm on the dimensions, then local runs from its 100 best designs.

Hernández et al. (2021), §2.2: MATLAB's ``ga`` on the eight dimensional parameters with the closest-point error E
as fitness (the problem's objective: one call = one "simulation"), then a local solver from each of the 100 best
distinct individuals, the best local minimum kept.  Here:

* GA: a feasible Latin-hypercube initial population (uniform draws in the box are rarely feasible: 2 % in
  example 1), binary tournament selection, SBX crossover and polynomial mutation (:mod:`.genetic_operators`), 5 %
  elitism; an infeasible child is not simulated and ranks by the paper's quadratic penalty, λ = 50 times the squared
  violation above every simulated value (its Eq. 17 adds λ g² to E; a slider-crank whose crank cannot turn has no
  E to add it to);
* local phase: SLSQP (scipy, bounded, the margins as inequality constraints, counted forward differences,
  :func:`~mechopt.optimize.sparse.local_search.local_slsqp`) instead of the paper's own two-phase solver of
  Eqs. 12-13, which needs the φ_i and the problem's derivatives, not only E;
* the budget: the GA gets ``ga_fraction`` of it, the local runs the rest, split by
  :func:`~mechopt.optimize.budget.run_multistart`; fewer than 100 starts when the rest cannot give each one
  ``4 (d + 1)`` simulations (a few SLSQP iterations).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.optimize.baselines.genetic_operators import polynomial_mutation, sbx_crossover
from mechopt.optimize.budget import BudgetExhausted, CountedProblem, run_multistart
from mechopt.optimize.sparse.local_search import local_slsqp

__all__ = ["minimize_paper000_hybrid"]


def minimize_paper000_hybrid(
    problem: CountedProblem,
    seed: int,
    *,
    pop_size: int | None = None,
    ga_fraction: float = 0.5,
    n_local: int = 100,
    penalty: float = 50.0,
    p_crossover: float = 0.8,
    elite_fraction: float = 0.05,
) -> OptimizeResult:
    """GA for ``ga_fraction`` of the budget, then SLSQP from its ``n_local`` best distinct feasible designs.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the initial population, the GA's operators and any extra local start.
    pop_size : int, optional
        Individuals per generation; default the budget of the GA over 10, between 20 and 200 (MATLAB's ``ga``
        uses 200 above five variables).
    ga_fraction : float, default 0.5
        Share of the budget given to the GA.
    n_local : int, default 100
        Local runs (the paper's 100 starting mechanisms), fewer when the budget left is small.
    penalty : float, default 50
        λ of the paper's Eq. 17, on the squared violation of an unsimulated infeasible child.
    p_crossover : float, default 0.8
        Probability that a pair of parents is crossed (MATLAB's crossover fraction).
    elite_fraction : float, default 0.05
        Share of the population copied unchanged to the next generation (MATLAB's default elite count).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``ngen`` (GA
        generations), ``nfev_ga`` (simulations of the GA) and ``nlocal`` (local runs).
    """
    rng = np.random.default_rng(seed)
    ga_budget = math.ceil(ga_fraction * problem.remaining)
    size = pop_size if pop_size is not None else int(np.clip(ga_budget // 10, 20, 200))
    generations = [0]
    try:
        with problem.sub_budget(ga_budget):
            _run_ga(problem, rng, size, penalty, p_crossover, max(1, round(elite_fraction * size)), generations)
    except BudgetExhausted as exc:
        if not exc.local:
            return problem.result(f"GA: {exc}", ngen=generations[0], nfev_ga=problem.nfev, nlocal=0)
    n_gen, nfev_ga = generations[0], problem.nfev
    n_starts = int(min(n_local, max(1, problem.remaining // (4 * (problem.dim + 1)))))
    starts = problem.best_designs(n_starts, min_distance=1e-2)
    if starts.shape[0] == 0:
        return problem.result("GA found no feasible design to start the local runs", ngen=n_gen, nfev_ga=nfev_ga,
                              nlocal=0)
    n, message = run_multistart(problem, starts, lambda x0: local_slsqp(problem, x0, ftol=1e-12),
                                rng=rng, min_share=problem.dim + 2)
    return problem.result(f"GA {n_gen} generations ({nfev_ga} simulations), {n} SLSQP runs: {message}",
                          ngen=n_gen, nfev_ga=nfev_ga, nlocal=n)


def _run_ga(problem: CountedProblem, rng: np.random.Generator, size: int, penalty: float, p_crossover: float,
            n_elite: int, generations: list[int]) -> None:
    """Generations until the (sub-)budget raises :class:`BudgetExhausted`, counted in ``generations[0]``."""

    def fitness(u: np.ndarray) -> float:
        return problem.penalised(problem.from_unit(u), reject=True, penalty=penalty, power=2.0)

    pop = problem.to_unit(problem.sample_feasible(size, rng))
    if pop.shape[0] < size:
        pop = np.vstack([pop, rng.random((size - pop.shape[0], problem.dim))])
    fit = np.array([fitness(u) for u in pop])
    while True:
        order = np.argsort(fit, kind="stable")
        children, child_fit = [pop[i] for i in order[:n_elite]], [fit[i] for i in order[:n_elite]]
        while len(children) < size:
            a, b = (pop[min(rng.choice(fit.size, 2, replace=False), key=lambda i: fit[i])] for _ in range(2))
            if rng.random() < p_crossover:
                a, b = sbx_crossover(a, b, rng)
            for child in (a, b)[: size - len(children)]:
                child = polynomial_mutation(child, rng)
                children.append(child)
                child_fit.append(fitness(child))
        pop, fit = np.array(children), np.array(child_fit)
        generations[0] += 1
