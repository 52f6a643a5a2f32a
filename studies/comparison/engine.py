"""Runs of an optimizer comparison at equal simulation budgets, scored against a study's ground truth.

Every method runs through :func:`mechopt.minimize` on the same problem (the same simulator, feasibility rules and
budget of simulator calls; a study's ``[compare] engine`` may name a faster engine standing in for its own).  Its
returned design is scored by its *true* objective (the problem's batch evaluator where it has one) and by the gap to
the brute-force optimum (:mod:`mechopt.studies.comparison.score`).  ``mechopt compare`` runs it, seeded.

Every run records the simulations it spent.  A run that stopped before its budget on an error (the method raised), or
a run of a library peer (``spends_whole_budget`` in the table of methods: its loop only ends when the budget is
spent) that ended with simulations left, is *unfinished*: it is printed and stored with its reason and marked "†" in
the tables, and it is never counted as a finished comparison (left out of the medians, and its method cannot reach
the optimum at that budget in the "simulations needed" count).  A method of ours that stops by its own rule (the
sparse pipeline when its refinement has converged) has finished: its calls are shown.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.errors import InputError, MechoptError
from mechopt.optimize.budget import BudgetExhausted, CountedProblem
from mechopt.optimize.ground_truth import GroundTruth
from mechopt.optimize.methods import DEFAULT_METHOD, METHODS, Method
from mechopt.optimize.minimize import minimize
from mechopt.optimize.problem import DesignProblem
from mechopt.studies.catalogue import Study
from mechopt.studies.comparison.score import gap_pct
from mechopt.surrogate.errors import SurrogateError

__all__ = ["OWN_METHOD", "Run", "check_limits", "check_methods", "compare", "compared_methods", "method_caps",
           "method_names", "run_one", "true_objective"]

#: The study's own method in the tables: its key ``method``, else the default of :func:`mechopt.minimize`.
OWN_METHOD = "mechopt"


def compared_methods() -> dict[str, Method]:
    """Every method of the table by the name ``mechopt compare`` gives it (mechopt's own: ``mechopt-auto``...)."""
    return {m.compare_name or m.name: m for m in METHODS.values()}


def method_names(text: str | None) -> list[str] | None:
    """``--methods``, comma separated, with mechopt's own methods also by the names ``--method`` and
    :func:`mechopt.minimize` know them (``auto`` is ``mechopt-auto``); None: all."""
    if not text:
        return None
    by_method = {m.name: name for name, m in compared_methods().items()}
    return [by_method.get(n, n) for n in text.split(",") if n]


def true_objective(problem: DesignProblem, design: np.ndarray | None) -> float:
    """The objective of a returned design as the score sees it: NaN unless feasible."""
    if design is None or not np.all(np.isfinite(design)) or not problem.feasible(design)[0]:
        return float("nan")
    batch = getattr(problem, "evaluate_batch", None)
    if batch is not None:
        return float(np.asarray(batch(np.asarray(design, float)[None, :]))[0])
    return float(problem.evaluate(np.asarray(design, float))[problem.objective])


@dataclass
class Run:
    """One method at one budget and seed."""

    method: str
    budget: int
    seed: int
    x: list[float] | None
    value: float
    gap_pct: float
    nfev: int
    wall_time_s: float
    message: str = ""
    finished: bool = True
    reason: str = ""

    def describe(self) -> str:
        """One line: the simulations spent, and why an unfinished run stopped (for the progress and the notes)."""
        text = f"{self.method} at budget {self.budget}, seed {self.seed}: {self.nfev} of {self.budget} simulations"
        return text if self.finished else f"{text}, stopped before its budget ({self.reason}); not counted"


@dataclass
class _Outcome:
    """What a guarded baseline run left behind: the error that stopped it, if any."""

    error: str = ""


def _one_line(exc: BaseException, limit: int = 200) -> str:
    """An exception as one line of at most about ``limit`` characters (a table note, not a traceback)."""
    text = " ".join(str(exc).split())
    text = text if len(text) <= limit else text[: limit - 1] + "…"
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _guarded(name: str, fn: Callable[..., OptimizeResult], outcome: _Outcome) -> Callable[..., OptimizeResult]:
    """The baseline ``fn`` as a :func:`minimize` method that never lets an error end the comparison.

    An exception of the method (a library's defect, a missing package) is recorded in ``outcome`` and the best
    design simulated until then is returned; ``mechopt compare`` then marks the run as
    unfinished.  Running the callable through :func:`minimize` is the same as running the method by its name.
    """

    def method(problem: CountedProblem, seed: int) -> OptimizeResult:
        try:
            res = fn(problem, seed)
        except BudgetExhausted as exc:  # a wrapper that let the budget's end through: the budget is spent
            res = problem.result(str(exc))
            if problem.nfev < problem.budget:
                outcome.error = _one_line(exc)
        except Exception as exc:  # any error of a peer is a result to report, not a crash of the comparison
            outcome.error = _one_line(exc)
            res = problem.result(f"{name} raised after {problem.nfev} simulations: {outcome.error}")
        return res

    method.__name__ = name
    return method


def method_caps(gp_max_budget: int | None = None, dim: int = 3) -> dict[str, int]:
    """Largest budget of the methods that have one (``max_budget`` in the table: those that refit a model on every
    sample at every step) at ``dim`` variables, by compare's names, lowered by ``gp_max_budget``."""
    caps = {name: m.max_budget(dim) for name, m in compared_methods().items() if m.max_budget is not None}
    if gp_max_budget is not None:
        caps = {k: min(v, int(gp_max_budget)) for k, v in caps.items()}
    return caps


def check_limits(methods: list[str] | None, budgets: Iterable[int], gp_max_budget: int | None = None,
                 dims: Iterable[int] = (3,)) -> None:
    """Refuse, before any run, a method named in ``methods`` at a budget beyond its limit (``max_budget`` in the
    table of methods: SMT's EGO, the Bayesian baseline).

    Beyond it a step (a model refit on every sample) takes more than about 3 s.  A ``gp_max_budget`` at or below the
    limit asks for the method to be run only up to it, so larger budgets are then skipped instead; when it is not
    named (every method), it is skipped beyond its limit and :func:`compare` says so.

    Parameters
    ----------
    methods : list of str, optional
        The methods asked for (None: every method).
    budgets : iterable of int
        The budgets asked for.
    gp_max_budget : int, optional
        ``--gp-max-budget``.
    dims : iterable of int
        The numbers of variables of the studies compared.

    Raises
    ------
    InputError
        One line naming the budget and the limit.
    """
    budgets = list(budgets)
    for name in methods or []:
        record = compared_methods().get(name)
        if record is None or record.max_budget is None:
            continue
        for dim in sorted(set(dims), reverse=True):
            limit = record.max_budget(dim)
            beyond = [b for b in budgets if b > limit]
            if beyond and (gp_max_budget is None or gp_max_budget > limit):
                raise InputError(f"{name} at budget {max(beyond)}: beyond its limit of {limit} simulations at {dim} "
                                 "variables (each step refits its model on every sample, over 3 s a step beyond); "
                                 f"lower --budgets or run it only up to N <= {limit} with --gp-max-budget N")


def check_methods(methods: list[str] | None, budgets: Iterable[int], gp_max_budget: int | None = None,
                  dims: Iterable[int] = (3,)) -> list[str]:
    """The methods to compare, in table order, after refusing an unknown one, one that does not take a study's
    number of variables, or one beyond its budget limit.

    Parameters
    ----------
    methods : list of str, optional
        The methods asked for (None: every method).
    budgets : iterable of int
        The budgets asked for.
    gp_max_budget : int, optional
        ``--gp-max-budget``.
    dims : iterable of int
        The numbers of variables of the studies compared.

    Returns
    -------
    list of str

    Raises
    ------
    InputError
        One line, before any run or ground truth (:func:`check_limits`).
    """
    table = compared_methods()
    names = [OWN_METHOD, *table]
    if methods:
        unknown = sorted(set(methods) - set(names))
        if unknown:
            raise InputError(f"unknown method {unknown[0]!r}; expected some of {', '.join(names)}")
        names = [n for n in names if n in methods]
        for name in methods:
            record = table.get(name)
            wrong = [d for d in dims if record is not None and not record.takes_dim(d)]
            if wrong:
                raise InputError(f"--methods {name}: method {record.name!r} handles {record.dims_text()} design "
                                 f"variables, a study compared has {wrong[0]}; use "
                                 f"{METHODS[DEFAULT_METHOD].compare_name} or a baseline")
    check_limits(methods, budgets, gp_max_budget, dims)
    return names


def _method_of(name: str, default: str, outcome: _Outcome) -> str | Callable[..., OptimizeResult]:
    """What :func:`minimize` runs for compare's ``name``: the study's own method, one of ours by its name, or a
    baseline guarded so that its error is a result (:func:`_guarded`)."""
    if name == OWN_METHOD:
        return default
    record = compared_methods()[name]
    return record.name if record.own else _guarded(record.name, record.function, outcome)


def run_one(problem: DesignProblem, truth: GroundTruth, name: str, budget: int, seed: int,
            default: str = DEFAULT_METHOD) -> Run:
    """One method at one budget and seed through :func:`minimize`, scored; an unfinished run says why.

    Parameters
    ----------
    problem : DesignProblem
    truth : GroundTruth
        The optimum the gap is measured to.
    name : str
        ``"mechopt"`` (the study's own method, ``default``) or a name of :func:`compared_methods`.
    budget : int
        Simulations the method is given.
    seed : int

    Returns
    -------
    Run
        ``nfev`` is the simulations spent; ``finished`` is False when the run stopped before its budget on an error,
        or when a peer that spends its whole budget left simulations unspent (``reason`` says why).
    """
    t0 = time.perf_counter()
    outcome = _Outcome()
    message = refused = ""
    try:
        res = minimize(problem, budget=budget, method=_method_of(name, default, outcome), seed=seed)
        x = np.asarray(res.x) if res.success else None
        nfev, message = int(res.nfev), " ".join(str(res.message).split())
    except (SurrogateError, MechoptError) as exc:
        # Too small a budget for one of our methods is a result of the comparison, not a crash of it; the table marks
        # it and says why, instead of an unexplained infinite gap.
        x, nfev, message = None, 0, _one_line(exc)
        refused = message
    finished, reason = True, ""
    spends_all = name != OWN_METHOD and compared_methods()[name].spends_whole_budget
    if refused:
        finished, reason = False, f"refused: {refused}"
    elif outcome.error:
        finished, reason = False, f"raised {outcome.error}"
    elif spends_all and nfev < budget:
        finished, reason = False, f"ended with {budget - nfev} simulations unspent: {message}"
    value = true_objective(problem, x)
    return Run(name, budget, seed, None if x is None else x.tolist(), value, gap_pct(problem, truth, value), nfev,
               time.perf_counter() - t0, message, finished, reason)


def compare(study: Study, truth: GroundTruth, budgets: list[int], seeds: int, methods: list[str] | None = None,
            progress=print, gp_max_budget: int | None = None) -> list[Run]:
    """Run every method at every budget and seed; returns the runs (see :func:`~mechopt.studies.comparison.tables.
    table`).

    ``gp_max_budget`` lowers the largest budget of the methods that refit a model at every call (``max_budget`` in
    the table of methods): a run of a hundred calls takes minutes where the others take seconds.  Each run's
    simulations spent are printed as it ends, with the reason of a run that stopped before its budget.

    Raises
    ------
    InputError
        An unknown method, or one named at a budget beyond its limit (:func:`check_limits`), before any run.
    """
    problem = study.problem
    names = check_methods(methods, budgets, gp_max_budget, [problem.dim])
    own = study.method or DEFAULT_METHOD
    table = compared_methods()
    if not methods:  # every method: the study's own once, and only those that take its number of variables
        names = [n for n in names if n == OWN_METHOD or (table[n].name != own and table[n].takes_dim(problem.dim))]
    caps = method_caps(gp_max_budget, problem.dim)
    for name in names:
        skipped = [b for b in budgets if b > caps.get(name, b)]
        if skipped:
            progress(f"  {name} runs up to {caps[name]} simulations: not run at "
                     f"{', '.join(str(b) for b in skipped)}")
    runs: list[Run] = []
    for budget in budgets:
        for seed in range(seeds):
            for name in names:
                if budget > caps.get(name, budget):
                    continue
                run = run_one(problem, truth, name, budget, seed, own)
                runs.append(run)
                own_stop = run.finished and run.nfev < run.budget and run.message
                progress(f"  {run.describe()}, {run.wall_time_s:.1f} s" + (f" ({run.message})" if own_stop else ""))
            progress(f"  budget {budget}, seed {seed}: done ({len(runs)} runs so far)")
    return runs
