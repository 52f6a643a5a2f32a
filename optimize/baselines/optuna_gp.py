"""Optuna's Gaussian-process sampler (single objective) as a budget-limited baseline, driven by ask/tell.

Configuration: ``GPSampler(seed=seed, n_startup_trials=10, deterministic_objective=False)``, Optuna's defaults: a
Matérn-5/2 Gaussian process with automatic relevance determination fitted by maximum a posteriori, log expected
improvement maximised by a quasi-Newton search from many starts, after 10 random trials (Optuna's documentation of
``optuna.samplers.GPSampler``, v4.2 and later).  The loop is ours, as for TPE: ``study.ask`` proposes a design in the
box, the cheap margins decide whether it is simulated, ``study.tell`` reports back, until
:class:`~mechopt.optimize.budget.CountedProblem` has spent the budget.

Constraint handling: Optuna's own (``trial.set_constraint``; GPSampler multiplies the improvement by the probability
that each constraint, modelled by its own process, is met).  GPSampler fits only completed trials, so an infeasible
design, which is not simulated, is told as completed with :func:`~optimize.baselines.library.rejected_value` (above
every simulated value) and with its violated constraint values, which its constraint models learn from; a failed
simulation the same, with a violated ``simulation`` constraint.  Without constraints a failed simulation is told as
``FAIL``.  PyTorch runs on one thread (the machine's cores are shared by the runs).  Needs the ``gp-peers`` extra.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.optimize.baselines.library import GP_PEERS_HINT, rejected_value, require
from mechopt.optimize.baselines.optuna_samplers import _silenced
from mechopt.optimize.baselines.torch_threads import one_torch_thread
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["minimize_optuna_gp"]


def _tell(optuna: Any, study: Any, trial: Any, problem: CountedProblem, x: np.ndarray) -> tuple[bool, bool]:
    """Simulate ``x`` when feasible and tell the trial; returns (rejected, failed)."""
    feasible = bool(problem.feasible(x)[0])
    f = problem.evaluate(x) if feasible else math.nan
    if not feasible:
        problem.penalised(x)  # counts the proposal, never simulates
    if problem.has_constraints:
        # A margin the constraint function could not give (NaN) counts as violated.
        for j, g in enumerate(np.nan_to_num(problem.margins(x), nan=-1.0)):
            trial.set_constraint(f"g{j}", -float(g))
        trial.set_constraint("simulation", 0.0 if (math.isfinite(f) or not feasible) else 1.0)
        study.tell(trial, f if math.isfinite(f) else rejected_value(problem, x))
    elif math.isfinite(f):
        study.tell(trial, f)
    else:
        study.tell(trial, state=optuna.trial.TrialState.FAIL)
    return not feasible, feasible and not math.isfinite(f)


def minimize_optuna_gp(
    problem: CountedProblem,
    seed: int,
    *,
    n_startup_trials: int = 10,
    deterministic_objective: bool = False,
) -> OptimizeResult:
    """Optuna's GPSampler with its native constraint handling, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the sampler (its random start-up trials and its acquisition search).
    n_startup_trials : int, default 10
        Random trials before the Gaussian process takes over (Optuna's default).
    deterministic_objective : bool, default False
        Fix the model's noise at its floor (Optuna's option for noise-free objectives; off by default).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``ntrials`` (trials
        asked), ``nrejected`` (infeasible trials, not simulated), ``nfailed`` (failed simulations).
    """
    optuna = require("optuna", "optuna_gp")
    require("torch", "optuna_gp", GP_PEERS_HINT)
    previous = _silenced(optuna)
    names = [f"x{i}" for i in range(problem.dim)]
    space = {n: optuna.distributions.FloatDistribution(float(lo), float(hi))
             for n, lo, hi in zip(names, problem.lower, problem.upper, strict=True)}
    counts = np.zeros(3, dtype=int)  # trials, rejected, failed
    message = "budget spent"
    with one_torch_thread():  # the machine's cores are shared by the runs
        try:
            with warnings.catch_warnings():
                # GPSampler's deterministic_objective is flagged experimental: no reason to warn at every run.
                warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
                sampler = optuna.samplers.GPSampler(seed=seed, n_startup_trials=n_startup_trials,
                                                    deterministic_objective=deterministic_objective)
                study = optuna.create_study(direction="minimize", sampler=sampler)
                while problem.remaining > 0:
                    trial = study.ask(space)
                    counts[0] += 1
                    x = np.array([trial.params[n] for n in names])
                    try:
                        counts[1:] += _tell(optuna, study, trial, problem, x)
                    except BudgetExhausted:
                        study.tell(trial, state=optuna.trial.TrialState.FAIL)
                        raise
        except BudgetExhausted as exc:
            message = str(exc)
        finally:
            optuna.logging.set_verbosity(previous)
    return problem.result(message, ntrials=int(counts[0]), nrejected=int(counts[1]), nfailed=int(counts[2]))
