"""nevergrad's recommended optimizer (NGOpt) and its CMA-ES as budget-limited baselines, driven by ask/tell.

The design is a bounded ``ng.p.Array`` (lower and upper bounds of the box; nevergrad's default bounding, which works
in a standardised space) initialised at a seeded random feasible design and seeded through its ``random_state``;
the optimizer is built with ``budget = problem.budget`` and ``num_workers=1`` and asked for one design at a time
until :class:`CountedProblem` has spent the budget.

* ``nevergrad_ngopt``: ``NGOpt``, nevergrad's documented default ("the optimizer we recommend"), a wizard that picks
  an algorithm from the dimension, budget, bounds and constraints: at 3 variables it picks SciPy's COBYLA up to 150
  calls, a metamodel-assisted CMA-ES (``ParametrizedMetaModel(CmaFmin2)``) from 200 to about 600 calls and a
  portfolio of NGOpt14 instances at 1870 calls.
* ``nevergrad_cma``: ``CMA`` (nevergrad's wrapper of pycma), default population ``4 + 3 ln d`` and step size.

Constraint handling: nevergrad's own cheap-constraint mechanism.  The feasibility test is registered with
``register_cheap_constraint``: ``ask`` resamples (then runs a small constraint-satisfaction search) until the
candidate is feasible, and nevergrad penalises a violating candidate in ``tell``.  A candidate still infeasible
after that is not simulated; it is told :func:`~studies.baselines.library.rejected_value` (above every simulated
value, growing with the violation), to which nevergrad adds its own penalty.  A failed simulation is told the same
value.

Known defect: nevergrad 1.0.12's metamodel step (``ParametrizedMetaModel``, which NGOpt picks at about 200 to 600
calls in 3-D) calls ``float()`` on a one-element array, a ``TypeError`` under numpy 2.4; the run then stops with the
best design so far and a message saying so (``nfev < budget``).
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.optimize.baselines.library import rejected_value, require
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["minimize_nevergrad_cma", "minimize_nevergrad_ngopt"]


class _Feasible:
    """Picklable cheap constraint for nevergrad (it warns about lambdas): True for a feasible design."""

    def __init__(self, problem: CountedProblem) -> None:
        self.problem = problem

    def __call__(self, x: np.ndarray) -> bool:
        return self.problem.feasible(np.asarray(x, dtype=float))


def _run(problem: CountedProblem, seed: int, optimizer_name: str, purpose: str) -> OptimizeResult:
    ng = require("nevergrad", purpose)
    # The start (nevergrad's init, where COBYLA and CMA-ES begin) is a seeded random feasible design, like the starts
    # of the other local baselines: the centre of the box need not be feasible, and a fixed start would make NGOpt's
    # deterministic COBYLA give one result for every seed.
    start = problem.sample_feasible(1, np.random.default_rng(seed))
    if start.shape[0] == 0:
        return problem.result("no feasible start found", nasked=0, nrejected=0)
    parametrization = ng.p.Array(init=start[0], lower=problem.lower.copy(), upper=problem.upper.copy())
    parametrization.random_state = np.random.RandomState(seed)
    if problem.has_constraints:
        parametrization.register_cheap_constraint(_Feasible(problem))
    optimizer = ng.optimizers.registry[optimizer_name](parametrization=parametrization, budget=problem.budget,
                                                      num_workers=1)
    n_asked = n_rejected = 0
    message = "budget spent"
    with warnings.catch_warnings():
        # Library chatter at every run: nevergrad's "could not bypass the constraint" (handled below), COBYLA's
        # parameter adjustments, pycma's injection notices.
        warnings.simplefilter("ignore")
        try:
            while problem.remaining > 0:
                candidate = optimizer.ask()
                n_asked += 1
                x = np.asarray(candidate.value, dtype=float)
                if not problem.feasible(x):
                    n_rejected += 1
                    problem.penalised(x)  # counts the proposal, never simulates
                    optimizer.tell(candidate, rejected_value(problem, x))
                    continue
                f = problem.evaluate(x)
                optimizer.tell(candidate, f if math.isfinite(f) else rejected_value(problem, x))
        except BudgetExhausted as exc:
            message = str(exc)
        except TypeError as exc:
            # nevergrad 1.0.12's metamodel (NGOpt's pick at ~200-600 calls in 3-D) calls float() on a 1-element
            # array, an error under numpy >= 2.4: the run stops there and says so (nfev < budget shows it).
            message = f"nevergrad failed after {problem.nfev} simulations: {exc}"
    return problem.result(f"{optimizer_name}: {message}", nasked=n_asked, nrejected=n_rejected)


def minimize_nevergrad_ngopt(problem: CountedProblem, seed: int, **_: Any) -> OptimizeResult:
    """nevergrad's NGOpt wizard with cheap constraints, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the parametrization's random state (all of nevergrad's draws).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nasked``,
        ``nrejected`` (candidates not simulated because infeasible).
    """
    return _run(problem, seed, "NGOpt", "nevergrad_ngopt")


def minimize_nevergrad_cma(problem: CountedProblem, seed: int, **_: Any) -> OptimizeResult:
    """nevergrad's CMA-ES with cheap constraints, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the parametrization's random state.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nasked``,
        ``nrejected``.
    """
    return _run(problem, seed, "CMA", "nevergrad_cma")
