"""Real-coded genetic algorithm followed by a local solver from its best designs (hybrid scheme of paper 000).

GA (Deb & Agrawal 1995; Deb 2001): binary tournament selection, simulated binary crossover (SBX), polynomial
mutation, elitism, Latin-hypercube initial population in the box.  As in paper 000, the GA only supplies starting
designs: when its share of the budget (``ga_fraction``) is spent, a local solver (Nelder-Mead or SLSQP) is run from
the best distinct designs it simulated, the rest of the budget split between them.

Constraint handling: static exterior penalty in the fitness, ``F + penalty * violation²`` (paper 000's
``λ·(Σ a_j C_j - C_0)²``).  An infeasible individual is simulated only if the problem allows
``simulate_infeasible``; otherwise it is rejected without simulation and gets ``infeasible_value + penalty *
violation²`` (a GA has no feasible anchor to continue the objective from).  The local phase uses the scheme of the
chosen solver (rejection for Nelder-Mead, native constraints for SLSQP).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.optimize import OptimizeResult
from scipy.stats import qmc

from mechopt.optimize.baselines.nelder_mead import local_nelder_mead
from mechopt.optimize.budget import BudgetExhausted, CountedProblem, run_multistart
from mechopt.optimize.sparse.local_search import local_slsqp

__all__ = ["minimize_genetic", "polynomial_mutation", "sbx_crossover"]


def sbx_crossover(
    a: np.ndarray, b: np.ndarray, rng: np.random.Generator, *, eta: float = 15.0
) -> tuple[np.ndarray, np.ndarray]:
    """Simulated binary crossover of two parents in the unit cube (bounded form of Deb & Agrawal 1995).

    Parameters
    ----------
    a, b : ndarray, shape (d,)
        Parents in ``[0, 1]^d``.
    rng : numpy.random.Generator
    eta : float, default 15
        Distribution index; larger keeps children closer to the parents.

    Returns
    -------
    tuple of ndarray
        Two children in ``[0, 1]^d``; each variable is crossed with probability 1/2.
    """
    c1, c2 = a.copy(), b.copy()
    for i in range(a.size):
        if rng.random() > 0.5 or abs(a[i] - b[i]) < 1e-14:
            continue
        y1, y2 = min(a[i], b[i]), max(a[i], b[i])
        u = rng.random()
        children = []
        # The spread factor's tail is cut at each bound so children never leave [0, 1] (bounded SBX).
        for distance in (y1, 1.0 - y2):
            beta = 1.0 + 2.0 * distance / (y2 - y1)
            alpha = 2.0 - beta ** -(eta + 1.0)
            if u <= 1.0 / alpha:
                betaq = (u * alpha) ** (1.0 / (eta + 1.0))
            else:
                betaq = (1.0 / (2.0 - u * alpha)) ** (1.0 / (eta + 1.0))
            children.append(betaq)
        lo = 0.5 * ((y1 + y2) - children[0] * (y2 - y1))
        hi = 0.5 * ((y1 + y2) + children[1] * (y2 - y1))
        lo, hi = float(np.clip(lo, 0.0, 1.0)), float(np.clip(hi, 0.0, 1.0))
        if rng.random() < 0.5:
            lo, hi = hi, lo
        c1[i], c2[i] = lo, hi
    return c1, c2


def polynomial_mutation(
    u: np.ndarray, rng: np.random.Generator, *, eta: float = 20.0, probability: float | None = None
) -> np.ndarray:
    """Bounded polynomial mutation (Deb & Goyal 1996) of a design in the unit cube.

    Parameters
    ----------
    u : ndarray, shape (d,)
        Design in ``[0, 1]^d``.
    rng : numpy.random.Generator
    eta : float, default 20
        Distribution index; larger gives smaller perturbations.
    probability : float, optional
        Per-variable mutation probability, default ``1 / d``.

    Returns
    -------
    ndarray, shape (d,)
        Mutated copy, still in ``[0, 1]^d``.
    """
    out = u.copy()
    pm = 1.0 / u.size if probability is None else probability
    for i in range(u.size):
        if rng.random() >= pm:
            continue
        y = out[i]
        r = rng.random()
        power = 1.0 / (eta + 1.0)
        if r < 0.5:
            xy = 1.0 - y  # 1 - delta1, delta1 = y being the distance to the lower bound
            val = 2.0 * r + (1.0 - 2.0 * r) * xy ** (eta + 1.0)
            dq = val**power - 1.0
        else:
            xy = y  # 1 - delta2, delta2 = 1 - y being the distance to the upper bound
            val = 2.0 * (1.0 - r) + 2.0 * (r - 0.5) * xy ** (eta + 1.0)
            dq = 1.0 - val**power
        out[i] = float(np.clip(y + dq, 0.0, 1.0))
    return out


def minimize_genetic(
    problem: CountedProblem,
    seed: int,
    *,
    pop_size: int = 20,
    ga_fraction: float = 0.7,
    n_local: int = 3,
    local: str = "nelder-mead",
    tournament_size: int = 2,
    p_crossover: float = 0.9,
    eta_crossover: float = 15.0,
    eta_mutation: float = 20.0,
    p_mutation: float | None = None,
    n_elite: int = 2,
    penalty: float | None = None,
) -> OptimizeResult:
    """Real-coded GA for ``ga_fraction`` of the budget, then a multistart local solver from its best designs.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the GA and of the local phase.
    pop_size : int, default 20
        Individuals per generation.
    ga_fraction : float, default 0.7
        Share of the budget given to the GA; the local solver gets the rest (all of it if the GA stops early).
    n_local : int, default 3
        Local searches, started from the best mutually distinct feasible designs of the GA.
    local : {"nelder-mead", "slsqp"}
        Local solver.
    tournament_size : int, default 2
        Individuals drawn per tournament.
    p_crossover : float, default 0.9
        Probability that a pair of parents is crossed (else copied).
    eta_crossover, eta_mutation : float
        Distribution indices of SBX and polynomial mutation.
    p_mutation : float, optional
        Per-variable mutation probability, default ``1 / d``.
    n_elite : int, default 2
        Best individuals copied unchanged to the next generation.
    penalty : float, optional
        Penalty coefficient of the fitness, default the problem's.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``ngen`` (GA
        generations), ``nfev_ga`` (simulations of the GA phase).
    """
    if local not in ("nelder-mead", "slsqp"):
        raise ValueError(f"local must be 'nelder-mead' or 'slsqp', got {local!r}")
    rng = np.random.default_rng(seed)

    def fitness(u: np.ndarray) -> float:
        return problem.penalised(problem.from_unit(u), reject=False, penalty=penalty, power=2.0)

    n_gen = 0
    try:
        with problem.sub_budget(math.ceil(ga_fraction * problem.remaining)):
            pop = qmc.LatinHypercube(problem.dim, rng=rng).random(pop_size)
            fit = np.array([fitness(u) for u in pop])
            while True:
                pop, fit = _next_generation(pop, fit, fitness, rng, pop_size=pop_size, n_elite=n_elite,
                                            tournament_size=tournament_size, p_crossover=p_crossover,
                                            eta_crossover=eta_crossover, eta_mutation=eta_mutation,
                                            p_mutation=p_mutation)
                n_gen += 1
    except BudgetExhausted as exc:
        if not exc.local:
            return problem.result(f"GA: {exc}", ngen=n_gen, nfev_ga=problem.nfev)
    return _local_phase(problem, rng, local=local, n_local=n_local, n_gen=n_gen)


def _next_generation(
    pop: np.ndarray,
    fit: np.ndarray,
    fitness: Callable[[np.ndarray], float],
    rng: np.random.Generator,
    *,
    pop_size: int,
    n_elite: int,
    tournament_size: int,
    p_crossover: float,
    eta_crossover: float,
    eta_mutation: float,
    p_mutation: float | None,
) -> tuple[np.ndarray, np.ndarray]:
    """The elite plus children bred by tournament selection, SBX and mutation, with their fitness.

    The keywords are those of :func:`minimize_genetic`; ``pop`` (in the unit cube) and ``fit`` are the current
    generation, ``fitness`` evaluates (and counts) one child.
    """

    def tournament() -> int:
        picks = rng.choice(fit.size, size=min(tournament_size, fit.size), replace=False)
        return int(picks[np.argmin(fit[picks])])

    order = np.argsort(fit, kind="stable")
    children = [pop[i].copy() for i in order[:n_elite]]
    child_fit = [fit[i] for i in order[:n_elite]]
    while len(children) < pop_size:
        a, b = pop[tournament()], pop[tournament()]
        if rng.random() < p_crossover:
            a, b = sbx_crossover(a, b, rng, eta=eta_crossover)
        for child in (a, b):
            if len(children) < pop_size:
                child = polynomial_mutation(child, rng, eta=eta_mutation, probability=p_mutation)
                children.append(child)
                child_fit.append(fitness(child))
    return np.array(children), np.array(child_fit)


def _local_phase(problem: CountedProblem, rng: np.random.Generator, *, local: str, n_local: int,
                 n_gen: int) -> OptimizeResult:
    """Multistart local solver from the GA's best distinct feasible designs, on the rest of the budget."""
    nfev_ga = problem.nfev
    starts = problem.best_designs(n_local, min_distance=1e-2)
    if starts.shape[0] == 0:
        return problem.result("GA found no feasible design to start the local solver", ngen=n_gen, nfev_ga=nfev_ga)

    def run_local(x0: np.ndarray) -> None:
        if local == "slsqp":
            local_slsqp(problem, x0)
        else:
            local_nelder_mead(problem, x0)

    n, message = run_multistart(problem, starts, run_local, rng=rng, min_share=problem.dim + 2)
    return problem.result(f"GA {n_gen} generations, local: {message}", ngen=n_gen, nfev_ga=nfev_ga)
