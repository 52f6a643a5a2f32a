"""pymoo's mixed-variable genetic algorithm: the ``pymoo_ga`` peer on a problem with discrete variables.

pymoo documents mixed variables through ``pymoo.core.mixed.MixedVariableGA`` on a problem declared with ``vars``
(``Real``, ``Integer``, ``Choice``; :mod:`~mechopt.optimize.baselines.mixed_space` maps each kind of mechopt
variable).  Configuration: pymoo's defaults -- ``MixedVariableSampling`` (uniform per variable),
``MixedVariableMating`` (SBX and polynomial mutation on reals, their rounded versions on integers, uniform crossover
and random reset on choices), ``MixedVariableDuplicateElimination``, ``FitnessSurvival`` (elitist) -- except the
population, :func:`~mechopt.optimize.baselines.pymoo_algorithms.default_pop_size` as for the continuous GA.

Constraints as in :mod:`~mechopt.optimize.baselines.pymoo_algorithms`: pymoo's feasibility-first rules on
``G = -margins <= 0``; an infeasible design is never simulated.  A design that an earlier generation simulated is
given its stored value without a second simulation (pymoo only removes duplicates within a generation).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.optimize.baselines.library import require
from mechopt.optimize.baselines.mixed_space import from_pymoo, pymoo_variables
from mechopt.optimize.baselines.pymoo_algorithms import default_pop_size, objective_value
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["minimize_pymoo_mixed_ga"]


def _mixed_problem(problem: CountedProblem) -> Any:
    """The counted problem as a pymoo ``Problem`` with mixed ``vars`` and one inequality constraint per margin."""
    core = require("pymoo.core.problem", "pymoo_ga")
    n_margins = max(problem.margins(0.5 * (problem.lower + problem.upper)).size, 1)

    class CountedMixed(core.Problem):
        def __init__(self) -> None:
            super().__init__(vars=pymoo_variables(problem), n_obj=1, n_ieq_constr=n_margins)

        def _evaluate(self, X: np.ndarray, out: dict, *args: Any, **kwargs: Any) -> None:
            F = np.empty((len(X), 1))
            G = np.zeros((len(X), n_margins))
            for i, values in enumerate(X):
                x = from_pymoo(problem, values)
                if problem.has_constraints:
                    G[i] = -problem.margins(x)
                F[i, 0] = objective_value(problem, x)
            out["F"] = F
            out["G"] = G

    return CountedMixed()


def minimize_pymoo_mixed_ga(problem: CountedProblem, seed: int, *, pop_size: int | None = None) -> OptimizeResult:
    """pymoo's ``MixedVariableGA`` with feasibility-first selection, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
        Carries ``variables`` (:class:`~mechopt.optimize.variable.Variable`) whose kinds decide pymoo's variables.
    seed : int
        Seed of pymoo's generator.
    pop_size : int, optional
        Individuals per generation, default :func:`default_pop_size`.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``ngen``.
    """
    mixed = require("pymoo.core.mixed", "pymoo_ga")
    pp = _mixed_problem(problem)
    algorithm = mixed.MixedVariableGA(pop_size=pop_size or default_pop_size(problem.budget))
    algorithm.setup(pp, termination=("n_gen", 10**9), seed=seed, verbose=False)
    n_gen = 0
    message = "budget spent"
    try:
        while problem.remaining > 0:
            pop = algorithm.ask()
            if len(pop) == 0:  # every offspring a duplicate: nothing new left to propose
                message = f"no new design proposed after {problem.nfev} simulations"
                break
            algorithm.evaluator.eval(pp, pop)
            algorithm.tell(infills=pop)
            n_gen += 1
    except BudgetExhausted as exc:
        message = str(exc)
    return problem.result(f"pymoo MixedVariableGA: {message}", ngen=n_gen)
