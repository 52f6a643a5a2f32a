"""Powell's conjugate-direction method with exterior penalty functions (paper 001).

As in the offset crank-slider study: the box is removed by Box's transformation ``x = L + (H - L) sin²(y)``
(``y`` unconstrained, every ``x`` inside the box), and the functional constraints enter a modified objective
``F + r * violation²`` (quadratic exterior penalty).  Where paper 001 uses one fixed penalty constant, the run here
is a short SUMT sequence of increasing coefficients ``r`` (each stage restarted from the previous optimum), the
textbook way of driving an exterior-penalty optimum onto the feasible side, followed by further feasible starts
while budget is left.

Constraint handling: exterior penalty.  The objective is called at an infeasible design only when the problem
allows ``simulate_infeasible``; otherwise it is taken at the design's projection on the feasible boundary (along the
segment from the start's best feasible design, cheap bisection), so ``F(p(x)) + r * violation²`` stays continuous
and no infeasible design is ever simulated.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.optimize import OptimizeResult, minimize

from mechopt.optimize.budget import BudgetExhausted, CountedProblem, run_multistart

__all__ = ["minimize_powell_penalty"]


def _to_box(problem: CountedProblem, y: np.ndarray) -> np.ndarray:
    """Box's transformation: any real ``y`` maps inside the box."""
    return problem.from_unit(np.sin(y) ** 2)


def _from_box(problem: CountedProblem, x: np.ndarray) -> np.ndarray:
    return np.arcsin(np.sqrt(np.clip(problem.to_unit(x), 0.0, 1.0)))


def _best_since(problem: CountedProblem, first: int, default: np.ndarray) -> np.ndarray:
    """Best feasible design simulated since history index ``first`` (the current start's own best)."""
    good = [e for e in problem.history[first:] if e.feasible and math.isfinite(e.f)]
    return min(good, key=lambda e: e.f).x if good else np.asarray(default, dtype=float)


def minimize_powell_penalty(
    problem: CountedProblem,
    seed: int,
    *,
    n_starts: int = 1,
    penalty_factors: Sequence[float] = (1e-2, 1.0, 1e2),
    xtol: float = 1e-6,
    ftol: float = 1e-10,
) -> OptimizeResult:
    """Multistart Powell on Box-transformed variables with a sequence of exterior penalties.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the feasible Latin-hypercube starts.
    n_starts : int, default 1
        Planned starts, each with an equal share of what is left; extra random starts use any budget left.
    penalty_factors : sequence of float, default (1e-2, 1, 1e2)
        Multipliers of ``problem.penalty`` for the successive penalty stages; a start's share is split evenly
        between the stages.
    xtol, ftol : float
        scipy Powell tolerances (``xtol`` on the transformed variables, radians).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nstarts``.
    """
    rng = np.random.default_rng(seed)
    starts = problem.sample_feasible(n_starts, rng)
    if starts.shape[0] == 0:
        return problem.result("no feasible start found", nstarts=0)
    factors = [float(r) for r in penalty_factors]

    def one_start(x0: np.ndarray) -> None:
        y = _from_box(problem, x0)
        first = len(problem.history)
        for stage, r in enumerate(factors):
            anchor = _best_since(problem, first, x0)
            # Lowest modified objective of this stage, the restart point of the next one if the share runs out.
            stage_best = [y, math.inf]

            def modified(yy: np.ndarray, c: float = problem.penalty * r, rec: list = stage_best,
                         a: np.ndarray = anchor) -> float:
                value = problem.penalised(_to_box(problem, yy), reject=False, penalty=c, power=2.0, anchor=a)
                if value < rec[1]:
                    rec[0], rec[1] = np.array(yy, dtype=float), value
                return value

            share = math.ceil(max(problem.available, 0) / (len(factors) - stage))
            try:
                with problem.sub_budget(share):
                    minimize(modified, y, method="Powell",
                             options={"xtol": xtol, "ftol": ftol, "maxfev": problem.max_proposals})
            except BudgetExhausted as exc:
                if not exc.local:
                    raise
            y = stage_best[0]

    n, message = run_multistart(problem, starts, one_start, rng=rng, min_share=2 * problem.dim + 2)
    return problem.result(message, nstarts=n)
