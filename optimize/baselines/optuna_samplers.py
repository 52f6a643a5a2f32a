"""Optuna's own samplers (TPE and CMA-ES) as budget-limited baselines, driven by Optuna's ask/tell interface.

Neither sampler caps simulator calls, so the loop is ours: ``study.ask`` proposes a design in the box (one
``FloatDistribution`` per variable), the cheap margins decide whether it is simulated, ``study.tell`` reports back,
until :class:`CountedProblem` has spent the budget.  Optuna's logging is silenced for the run.

TPE (Bergstra et al. 2011; Watanabe 2023), configuration: ``TPESampler(multivariate=True, seed=seed,
n_startup_trials=10)``.  Multivariate TPE is what Optuna documents as the better choice for single-objective problems
(and its default for them from v4 on); 10 random start-up trials is Optuna's default and about a sixth of a 60-call
budget.  Constraint handling: Optuna's own (constrained TPE, Optuna >= 3; ``trial.set_constraint`` since v5).  Every
trial carries its margins as constraint values (``-margin``, violated when > 0); an infeasible design is not simulated
and is told as ``PRUNED``: TPE ranks such trials below every feasible one, by their total violation, when it splits
good from bad trials.  A design whose simulation failed is told the same way with a violated ``simulation``
constraint, so TPE moves away from it.

CMA-ES (Hansen & Ostermeier 2001; Optuna's ``CmaEsSampler`` on the ``cmaes`` package), configuration:
``CmaEsSampler(seed=seed, n_startup_trials=1, sigma0=None, popsize=None)`` -- Optuna's defaults: the mean starts at
the centre of the box, ``sigma0`` is a sixth of each variable's range (Optuna works in the unit cube), the population
is ``4 + 3 ln d`` (7 for d = 3), which gives 8 generations in 60 calls.  The sampler ignores constraints (it only
warns when they are set), so they are handled outside it, by one of two documented schemes (``infeasible`` option):

* ``"resample"``: an infeasible design is not simulated and is told as ``FAIL``; Optuna's CMA-ES only counts
  completed trials towards a generation, so the next ask draws a fresh candidate from the same search distribution --
  Hansen's resampling of infeasible solutions.
* ``"penalty"`` (default): an infeasible design is not simulated and is told as completed with the value of
  :func:`~optimize.baselines.library.rejected_value` (above every simulated value, growing with the violation), so it
  ranks last in its generation.

The penalty is the default because the optima of mechanism problems sit on constraints: on the test problem whose
minimum lies on a linear constraint (tests/optimize/test_baselines.py, QUAD), 200 calls leave a median gap of 3e-2
with resampling and 2.5e-3 with the penalty (seeds 0-2), 500 calls 1.4e-5 and 1e-7.

A failed simulation is told as ``FAIL`` in both schemes.

Discrete variables are declared as Optuna documents them (:mod:`~mechopt.optimize.baselines.mixed_space`): an
integer as ``IntDistribution`` (``suggest_int``), a catalogue as ``CategoricalDistribution`` (``suggest_categorical``),
a drawing grid as ``FloatDistribution(step=)`` (``suggest_float(step=)``), so every trial is an allowed design.  A
trial that repeats a simulated design is told its stored value (the counted problem does not simulate it again).
"""

from __future__ import annotations

import math
import warnings
from typing import Any

from scipy.optimize import OptimizeResult

from mechopt.errors import InputError
from mechopt.optimize.baselines.library import rejected_value, require
from mechopt.optimize.baselines.mixed_space import from_optuna, optuna_space
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["minimize_optuna_cmaes", "minimize_optuna_tpe"]


def _silenced(optuna: Any) -> int:
    previous = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.ERROR)
    return previous


def _run(problem: CountedProblem, optuna: Any, sampler: Any, *, constraints: bool, infeasible: str) -> OptimizeResult:
    """Ask/tell loop shared by the samplers; returns the problem's result."""
    TrialState = optuna.trial.TrialState
    space = optuna_space(optuna, problem)
    study = optuna.create_study(direction="minimize", sampler=sampler)
    n_trials = n_rejected = 0
    message = "budget spent"
    try:
        while problem.remaining > 0:
            trial = study.ask(space)
            n_trials += 1
            x = from_optuna(problem, trial.params)
            ok = bool(problem.feasible(x)[0])
            if constraints:
                for j, g in enumerate(problem.margins(x)):
                    trial.set_constraint(f"g{j}", -float(g))
            if not ok:
                n_rejected += 1
                problem.penalised(x)  # counts the proposal, never simulates
                if constraints:
                    study.tell(trial, state=TrialState.PRUNED)
                elif infeasible == "penalty":
                    study.tell(trial, rejected_value(problem, x))
                else:
                    study.tell(trial, state=TrialState.FAIL)
                continue
            try:
                f = problem.evaluate(x)
            except BudgetExhausted:
                study.tell(trial, state=TrialState.FAIL)
                raise
            if math.isfinite(f):
                if constraints:
                    trial.set_constraint("simulation", 0.0)
                study.tell(trial, f)
            elif constraints:
                trial.set_constraint("simulation", 1.0)
                study.tell(trial, state=TrialState.PRUNED)
            else:
                study.tell(trial, state=TrialState.FAIL)
    except BudgetExhausted as exc:
        message = str(exc)
    return problem.result(message, ntrials=n_trials, nrejected=n_rejected)


def minimize_optuna_tpe(
    problem: CountedProblem,
    seed: int,
    *,
    n_startup_trials: int = 10,
    n_ei_candidates: int = 24,
    multivariate: bool = True,
) -> OptimizeResult:
    """Optuna's tree-structured Parzen estimator with its native constraint handling, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the sampler.
    n_startup_trials : int, default 10
        Random trials before TPE takes over (Optuna's default).
    n_ei_candidates : int, default 24
        Candidates drawn from the good-trial density per proposal (Optuna's default).
    multivariate : bool, default True
        Joint Parzen estimator over all variables (Optuna's recommendation for single-objective problems).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``ntrials`` (trials
        asked), ``nrejected`` (infeasible trials, not simulated).
    """
    optuna = require("optuna", "optuna_tpe")
    previous = _silenced(optuna)
    try:
        with warnings.catch_warnings():
            # multivariate TPE is flagged experimental, which is no reason to warn at every run.
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            sampler = optuna.samplers.TPESampler(seed=seed, n_startup_trials=n_startup_trials,
                                                 n_ei_candidates=n_ei_candidates, multivariate=multivariate)
            return _run(problem, optuna, sampler, constraints=problem.has_constraints, infeasible="constraint")
    finally:
        optuna.logging.set_verbosity(previous)


def minimize_optuna_cmaes(
    problem: CountedProblem,
    seed: int,
    *,
    infeasible: str = "penalty",
    popsize: int | None = None,
    sigma0: float | None = None,
    n_startup_trials: int = 1,
) -> OptimizeResult:
    """Optuna's CMA-ES sampler, infeasible designs resampled (or penalised) without simulation.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the sampler.
    infeasible : {"resample", "penalty"}, default "penalty"
        What the sampler is told about an infeasible design (see the module docstring).
    popsize : int, optional
        Population per generation, default CMA-ES's ``4 + floor(3 ln d)``.
    sigma0 : float, optional
        Initial step size in the unit cube of the box (Optuna normalises every variable to [0, 1]), default 1/6.
    n_startup_trials : int, default 1
        Random trials before CMA-ES takes over (Optuna's default).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``ntrials``,
        ``nrejected``.
    """
    if infeasible not in ("resample", "penalty"):
        raise InputError(f"infeasible must be 'resample' or 'penalty', got {infeasible!r}")
    optuna = require("optuna", "optuna_cmaes")
    require("cmaes", "optuna_cmaes")
    previous = _silenced(optuna)
    try:
        sampler = optuna.samplers.CmaEsSampler(seed=seed, popsize=popsize, sigma0=sigma0,
                                               n_startup_trials=n_startup_trials)
        return _run(problem, optuna, sampler, constraints=False, infeasible=infeasible)
    finally:
        optuna.logging.set_verbosity(previous)
