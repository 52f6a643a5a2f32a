"""Optimizer comparison at equal simulation budgets, scored against a study's ground truth.

Every method runs through :func:`mechopt.minimize` on the same problem (the same simulator, feasibility rules and
budget of simulator calls; a study's ``[compare] engine`` may name a faster engine standing in for its own).  Its
returned design is scored by its *true* objective (the problem's batch evaluator where it has one) and by the gap to
the brute-force optimum.  The table and the figure are produced by code, from scratch and seeded:
``mechopt compare``.

Every run records the simulations it spent.  A run that stopped before its budget on an error (the method raised), or
a run of a library peer (:data:`SPENDS_WHOLE_BUDGET`, whose loops only end when the budget is spent) that ended with
simulations left, is *unfinished*: it is printed and stored with its reason and marked "†" in the tables, and it is
never counted as a finished comparison (left out of the medians, and its method cannot reach the optimum at that
budget in the "simulations needed" count).  A method of ours that stops by its own rule (the sparse pipeline when
its refinement has converged) has finished: its calls are shown.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.errors import InputError, MechoptError
from mechopt.optimize.arguments import DEFAULT_METHOD, handles_dim
from mechopt.optimize.baselines import BASELINES, LIBRARY_BASELINES
from mechopt.optimize.budget import BudgetExhausted, CountedProblem
from mechopt.optimize.ground_truth import GroundTruth
from mechopt.optimize.minimize import minimize
from mechopt.optimize.problem import DesignProblem
from mechopt.studies.catalogue import Study
from mechopt.surrogate.errors import SurrogateError

#: Bayesian optimisation (in-house GP, SMT's EGO) refits a Gaussian process on all samples at every step (cubic
#: cost): it is run up to this budget only, as in the literature, where it is used for small budgets.
BAYESIAN_MAX_BUDGET = 200
#: SMT's EGO refits its Kriging model (a hyperparameter search per variable) at every step, a cost that grows with the
#: cube of the simulations and with the dimension: compare runs it up to the budget where a step still takes under
#: about 3 s of CPU, and refuses a larger one it is explicitly asked for.  CPU time per step, one BLAS thread, on
#: the 2-core machine under heavy load (2026-11-25): 3-D 1.0 s at 20 samples, 2.5 s at 100, 3.1 s at 120, 4.3 s at
#: 140; 5-D 1.5 s at 30, 2.4 s at 60, 3.2 s at 70; 8-D 1.7 s at 20, 3.2 s at 30, 3.9 s at 40.  Less loaded
#: (benchmarks/bench_peer_budgets.py, BENCHMARKS.md): 3-D 1.8 s at 100, 8-D 2.4 s at 30.  The limit up to 3
#: variables:
EGO_MAX_BUDGET = 100
#: The limits as (most variables, largest budget): 100 up to 3 variables, 60 at 4 or 5, 30 from 6 on (measured at
#: 3, 5 and 8 variables; beyond 8 a step at 30 samples is not measured and may cost more).
EGO_MAX_BUDGETS = ((3, EGO_MAX_BUDGET), (5, 60), (12, 30))
#: The peers from maintained libraries: each asks for designs until the budget is spent (a test per peer checks
#: ``nfev == budget``), so a run of one of them that ends with simulations left was stopped by an error or a defect,
#: never by a rule of its own.
SPENDS_WHOLE_BUDGET = frozenset(LIBRARY_BASELINES)
#: The mark of an unfinished run in the tables.
UNFINISHED_MARK = "†"



#: mechopt's methods by the names compare gives them; ``"mechopt"`` is the study's own (its key ``method``, else
#: the default of :func:`mechopt.minimize`).
OUR_METHODS = {"mechopt-auto": "auto", "mechopt-sparse": "sparse", "mechopt-global": "sparse-global"}


def method_names(text: str | None) -> list[str] | None:
    """``--methods``, comma separated, with mechopt's own methods also by the names ``--method`` and
    :func:`mechopt.minimize` know them (``auto`` is ``mechopt-auto``); None: all."""
    if not text:
        return None
    by_method = {method: name for name, method in OUR_METHODS.items()}
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


def known_truth(problem: DesignProblem) -> GroundTruth | None:
    """The optimum a problem declares (``f_min``, ``x_min``: test functions, a synthesis against a known target)."""
    f_min = getattr(problem, "f_min", None)
    if f_min is None or not np.isfinite(f_min):
        return None
    x = np.atleast_2d(np.asarray(getattr(problem, "x_min", np.full((1, problem.dim), np.nan)), dtype=float))[0]
    return GroundTruth(x=x.tolist(), fun=float(f_min), grid_x=x.tolist(), grid_fun=float(f_min), step=0.0,
                       n_evaluated=0, n_feasible=0, wall_time_s=0.0, key="known")


def declared_truth(study: Study) -> GroundTruth | None:
    """The optimum a study file declares in ``[compare] known_optimum`` (a brute force recorded with the study),
    simulated here so that the score's reference is this engine's own value."""
    known = study.section("compare").get("known_optimum")
    if not isinstance(known, dict):
        return None
    problem = study.problem
    try:
        x = np.array([float(known[v]) for v in problem.names])
    except (KeyError, TypeError, ValueError):
        raise InputError(f"{study.name}: [compare] known_optimum must give {list(problem.names)}") from None
    fun = float(problem.evaluate(x)[problem.objective])
    return GroundTruth(x=x.tolist(), fun=fun, grid_x=x.tolist(), grid_fun=fun, step=0.0, n_evaluated=0,
                       n_feasible=0, wall_time_s=0.0, key="declared")


def tolerance(problem: DesignProblem, truth: GroundTruth) -> float:
    """How close to the optimum counts as reaching it: 0.5 % of the function's range over the box where the problem
    declares it (test functions), 0.5 % of the optimum, or 1e-6 absolute where the optimum is 0."""
    f_range = getattr(problem, "f_range", None)
    if f_range is not None and np.isfinite(f_range) and f_range > 0:
        return 0.005 * float(f_range)
    return 0.005 * abs(truth.fun) if truth.fun else 1e-6


def gap_pct(problem: DesignProblem, truth: GroundTruth, value: float) -> float:
    """The gap in per cent: of the range over the box (test functions), of the optimum, or ×1e6 absolute at 0."""
    if not np.isfinite(value):
        return float("nan")
    f_range = getattr(problem, "f_range", None)
    if f_range is not None and np.isfinite(f_range) and f_range > 0:
        return 100 * (value - truth.fun) / f_range
    return 100 * (value / truth.fun - 1) if truth.fun else 100 * value


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


def ego_max_budget(dim: int) -> int:
    """The largest budget ``mechopt compare`` runs SMT's EGO at on a problem of ``dim`` variables (see
    :data:`EGO_MAX_BUDGETS`)."""
    for most, budget in EGO_MAX_BUDGETS:
        if dim <= most:
            return budget
    return EGO_MAX_BUDGETS[-1][1]


def method_caps(gp_max_budget: int | None = None, dim: int = 3) -> dict[str, int]:
    """Largest budget of the methods that have one (the Gaussian-process methods) at ``dim`` variables, lowered by
    ``gp_max_budget``."""
    caps = {"bayesian": BAYESIAN_MAX_BUDGET, "smt_ego": ego_max_budget(dim)}
    if gp_max_budget is not None:
        caps = {k: min(v, int(gp_max_budget)) for k, v in caps.items()}
    return caps


def check_limits(methods: list[str] | None, budgets: Iterable[int], gp_max_budget: int | None = None,
                 dims: Iterable[int] = (3,)) -> None:
    """Refuse, before any run, SMT's EGO named in ``methods`` at a budget beyond its limit (:func:`ego_max_budget`).

    Beyond it an EGO step (a Kriging refit on every sample) takes more than about 3 s.  A ``gp_max_budget`` at
    or below the limit asks for EGO to be run only up to it, so larger budgets are then skipped for EGO instead;
    when EGO is not named (every method), it is skipped beyond its limit and :func:`compare` says so.

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
    if not methods or "smt_ego" not in methods:
        return
    budgets = list(budgets)
    for dim in sorted(set(dims), reverse=True):
        limit = ego_max_budget(dim)
        if gp_max_budget is not None and gp_max_budget <= limit:
            continue
        beyond = [b for b in budgets if b > limit]
        if beyond:
            raise InputError(f"smt_ego at budget {max(beyond)}: beyond its limit of {limit} simulations at {dim} "
                             "variables (each EGO step refits Kriging on every sample, over 3 s a step beyond); lower "
                             f"--budgets or run it only up to N <= {limit} with --gp-max-budget N")


def check_methods(methods: list[str] | None, budgets: Iterable[int], gp_max_budget: int | None = None,
                  dims: Iterable[int] = (3,)) -> list[str]:
    """The methods to compare, in table order, after refusing an unknown one or EGO beyond its limit.

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
    names = ["mechopt", *OUR_METHODS, *BASELINES]
    if methods:
        unknown = sorted(set(methods) - set(names))
        if unknown:
            raise InputError(f"unknown method {unknown[0]!r}; expected some of {', '.join(names)}")
        names = [n for n in names if n in methods]
        for name in methods:
            wrong = [d for d in dims if name in OUR_METHODS and not handles_dim(OUR_METHODS[name], d)]
            if wrong:
                raise InputError(f"--methods {name}: method {OUR_METHODS[name]!r} handles 2 to 4 design variables, a "
                                 f"study compared has {wrong[0]}; use mechopt-auto or a baseline")
    check_limits(methods, budgets, gp_max_budget, dims)
    return names


def run_one(problem: DesignProblem, truth: GroundTruth, name: str, budget: int, seed: int,
            default: str = DEFAULT_METHOD) -> Run:
    """One method at one budget and seed through :func:`minimize`, scored; an unfinished run says why.

    Parameters
    ----------
    problem : DesignProblem
    truth : GroundTruth
        The optimum the gap is measured to.
    name : str
        ``"mechopt"`` (the study's own method, ``default``), a name of :data:`OUR_METHODS` or of :data:`BASELINES`.
    budget : int
        Simulations the method is given.
    seed : int

    Returns
    -------
    Run
        ``nfev`` is the simulations spent; ``finished`` is False when the run stopped before its budget on an error,
        or when a peer of :data:`SPENDS_WHOLE_BUDGET` left simulations unspent (``reason`` says why).
    """
    t0 = time.perf_counter()
    outcome = _Outcome()
    message = refused = ""
    try:
        if name in BASELINES:
            method: Any = _guarded(name, BASELINES[name], outcome)
        else:
            method = default if name == "mechopt" else OUR_METHODS[name]
        res = minimize(problem, budget=budget, method=method, seed=seed)
        x = np.asarray(res.x) if res.success else None
        nfev, message = int(res.nfev), " ".join(str(res.message).split())
    except (SurrogateError, MechoptError) as exc:
        # Too small a budget for one of our methods is a result of the comparison, not a crash of it; the table marks
        # it and says why, instead of an unexplained infinite gap.
        x, nfev, message = None, 0, _one_line(exc)
        refused = message
    finished, reason = True, ""
    if refused:
        finished, reason = False, f"refused: {refused}"
    elif outcome.error:
        finished, reason = False, f"raised {outcome.error}"
    elif name in SPENDS_WHOLE_BUDGET and nfev < budget:
        finished, reason = False, f"ended with {budget - nfev} simulations unspent: {message}"
    value = true_objective(problem, x)
    return Run(name, budget, seed, None if x is None else x.tolist(), value, gap_pct(problem, truth, value), nfev,
               time.perf_counter() - t0, message, finished, reason)


def compare(study: Study, truth: GroundTruth, budgets: list[int], seeds: int, methods: list[str] | None = None,
            progress=print, gp_max_budget: int | None = None) -> list[Run]:
    """Run every method at every budget and seed; returns the runs (see :func:`table`).

    ``gp_max_budget`` lowers the largest budget the Gaussian-process methods (``bayesian``, ``smt_ego``) run at:
    they refit at every call, and a run of a hundred calls takes minutes where the others take seconds.  Each run's
    simulations spent are printed as it ends, with the reason of a run that stopped before its budget.

    Raises
    ------
    InputError
        An unknown method, or SMT's EGO named at a budget beyond its limit (:func:`check_limits`), before any run.
    """
    problem = study.problem
    names = check_methods(methods, budgets, gp_max_budget, [problem.dim])
    own = study.method or DEFAULT_METHOD
    if not methods:  # every method: ours once each, and the line models only where they apply (2 to 4 variables)
        names = [n for n in names if OUR_METHODS.get(n) != own
                 and (n not in OUR_METHODS or handles_dim(OUR_METHODS[n], problem.dim))]
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
                run = run_one(problem, truth, name, budget, seed, study.method or DEFAULT_METHOD)
                runs.append(run)
                own_stop = run.finished and run.nfev < run.budget and run.message
                progress(f"  {run.describe()}, {run.wall_time_s:.1f} s" + (f" ({run.message})" if own_stop else ""))
            progress(f"  budget {budget}, seed {seed}: done ({len(runs)} runs so far)")
    return runs


def table(runs: list[Run], problem: DesignProblem | None = None, truth: GroundTruth | None = None) -> list[dict]:
    """One row per method and budget: median / best / worst true value, gap, share within 1 %, calls, time, and
    whether the median run reached the optimum (see :func:`tolerance`).

    Only finished runs are counted (:class:`Run`); ``unfinished`` counts the others and ``complete`` is False
    when there is one, in which case the row never counts as reaching the optimum (:func:`simulations_needed`).
    """
    tol = tolerance(problem, truth) if problem is not None and truth is not None else None
    rows = []
    for method in dict.fromkeys(r.method for r in runs):
        for budget in sorted({r.budget for r in runs if r.method == method}):
            every = [r for r in runs if r.method == method and r.budget == budget]
            sel = [r for r in every if r.finished]
            t = np.array([r.value for r in sel], dtype=float)
            gaps = np.array([r.gap_pct for r in sel], dtype=float)
            finite = np.isfinite(t)
            calls = [r.nfev for r in every]
            rows.append({
                "method": method, "budget": budget, "runs": len(every),
                "median_value": float(np.median(t[finite])) if finite.any() else float("nan"),
                "best_value": float(np.min(t[finite])) if finite.any() else float("nan"),
                "worst_value": float(np.max(t[finite])) if finite.any() else float("nan"),
                "median_gap_pct": float(np.median(np.where(finite, gaps, np.inf))) if sel else float("nan"),
                "within_1pct": float(np.mean(np.where(finite, gaps, np.inf) <= 1.0)) if sel else float("nan"),
                "median_calls": float(np.median(calls)),
                "max_calls": int(max(calls)),
                "median_wall_s": float(np.median([r.wall_time_s for r in every])),
                "median_reached": bool(tol is not None and finite.sum() * 2 > len(sel)
                                       and np.median(np.where(finite, t, np.inf)) <= truth.fun + tol),
                "unfinished": len(every) - len(sel),
                "complete": len(sel) == len(every),
            })
    return rows


def unfinished_runs(runs: list[Run]) -> list[Run]:
    """The runs that stopped before their budget and are not counted (:class:`Run`)."""
    return [r for r in runs if not r.finished]


def unfinished_methods(rows: list[dict]) -> set[str]:
    """Methods with at least one unfinished run in ``rows`` (rows of :func:`table`; older rows count as complete)."""
    return {r["method"] for r in rows if not r.get("complete", True)}


def _notes(runs: list[Run]) -> str:
    """The unfinished runs, one line each, under a table."""
    bad = unfinished_runs(runs)
    if not bad:
        return ""
    return (f"\n{UNFINISHED_MARK} {len(bad)} run(s) stopped before spending their budget and are not counted (left out "
            "of the medians; the method cannot reach the optimum at that budget):\n\n"
            + "".join(f"- {r.describe()}\n" for r in bad))


def markdown(rows: list[dict], truth: GroundTruth, study: Study, seeds: int, runs: list[Run] | None = None) -> str:
    """The comparison table in Markdown, with its provenance and (given ``runs``) a note per unfinished run."""
    problem = study.problem
    obj = problem.objective
    engine = problem.settings().get("engine", "its own")
    lines = [f"Ground truth {obj} {truth.fun:.6g} at {problem.describe(np.array(truth.x))} (brute force, grid "
             f"{truth.step:g} + polish). Simulator: {engine}; {seeds} seeds per method and budget; every returned "
             f"design scored by its true {obj}.", "",
             f"| method | budget | runs | median {obj} | best | worst | median gap | within 1 % | calls (median / max)"
             f" | wall (s) | stopped early {UNFINISHED_MARK} |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        unfinished = r.get("unfinished", 0)
        stopped = f"{unfinished} {UNFINISHED_MARK}" if unfinished else "0"
        if unfinished == r["runs"]:  # no finished run: nothing to report but the calls
            scores = "— | — | — | — | —"
        else:
            scores = (f"{r['median_value']:.6g} | {r['best_value']:.6g} | {r['worst_value']:.6g} | "
                      f"{r['median_gap_pct']:+.2f} % | {100 * r['within_1pct']:.0f} %")
        lines.append(f"| {r['method']} | {r['budget']} | {r['runs']} | {scores} | {r['median_calls']:.0f} / "
                     f"{r['max_calls']} | {r['median_wall_s']:.2f} | {stopped} |")
    return "\n".join(lines) + "\n" + (_notes(runs) if runs else "")


def pivot_markdown(rows: list[dict]) -> str:
    """Median gap to the true optimum per method (rows) and budget (columns), for a quick read; "†": some runs of
    that cell stopped before their budget and are left out of its median."""
    budgets = sorted({r["budget"] for r in rows})
    lines = ["| method | " + " | ".join(f"{b} calls" for b in budgets) + " |",
             "|---|" + "---|" * len(budgets)]
    for method in dict.fromkeys(r["method"] for r in rows):
        cells = []
        for b in budgets:
            sel = [r for r in rows if r["method"] == method and r["budget"] == b]
            if not sel:
                cells.append("—")
            elif sel[0].get("complete", True):
                cells.append(f"{sel[0]['median_gap_pct']:+.2f} %")
            elif sel[0].get("unfinished", 0) < sel[0]["runs"]:
                cells.append(f"{sel[0]['median_gap_pct']:+.2f} % {UNFINISHED_MARK}")
            else:
                cells.append(f"— {UNFINISHED_MARK}")
        lines.append(f"| {method} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot_gaps(rows: list[dict], path: Path, threshold_pct: float = 0.5) -> Path:
    """Median gap to the ground truth against the number of simulations, log scales, one curve per method;
    ``threshold_pct`` is the gap that counts as reaching the optimum (:func:`tolerance`, in the gap's units)."""
    from mechopt.report.plots import plt
    from mechopt.sim.figure_file import save_figure

    fig, ax = plt.subplots(figsize=(10, 5.2))
    for i, method in enumerate(dict.fromkeys(r["method"] for r in rows)):
        sel = [r for r in rows if r["method"] == method]
        b = np.array([r["budget"] for r in sel])
        # An unfinished cell is not a finished comparison: a gap in the curve, not a point.
        g = np.array([max(r["median_gap_pct"], 1e-8) if r.get("complete", True) else np.nan for r in sel])
        style = dict(lw=3, color="k", marker="o") if method == "mechopt" else dict(lw=1.3, marker=".")
        ax.plot(b, np.where(np.isfinite(g), g, np.nan), label=method, color=None if method != "mechopt" else "k",
                linestyle="-" if i < 10 else "--", **{k: v for k, v in style.items() if k != "color"})
    ax.axhline(threshold_pct, color="C3", ls=":", lw=1, label="reached: within the tolerance of the optimum")
    ax.set_xscale("log")
    ax.set_yscale("log")
    budgets = sorted({int(r["budget"]) for r in rows})
    ax.set_xticks(budgets)
    ax.set_xticklabels([str(b) for b in budgets])
    ax.minorticks_off()
    ax.set_xlabel("simulator calls (budget)")
    ax.set_ylabel("median gap to the true optimum (%, or 100 f where f* = 0; floor 1e-8)")
    ax.set_title("Optimizers at equal simulation budgets (median over seeds)", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    return save_figure(fig, path)


def simulations_needed(rows: list[dict]) -> dict[str, int | None]:
    """Per method, the fewest budget from which on the median run reaches the optimum at every larger budget too
    (None: not at the largest budget).  A method that reaches it once and loses it at a larger budget is not
    counted as having reached it there, nor at a budget where some of its runs stopped before their budget."""
    out: dict[str, int | None] = {}
    for method in dict.fromkeys(r["method"] for r in rows):
        by_budget = sorted((r["budget"], bool(r["median_reached"]) and r.get("complete", True))
                           for r in rows if r["method"] == method)
        needed = None
        for budget, reached in reversed(by_budget):
            if not reached:
                break
            needed = budget
        out[method] = needed
    return out


def largest_budgets(rows: list[dict]) -> dict[str, int]:
    """Per method, the largest budget it ran at (the Gaussian-process methods stop below the others)."""
    out: dict[str, int] = {}
    for r in rows:
        out[r["method"]] = max(out.get(r["method"], 0), int(r["budget"]))
    return out


def _largest(budgets: dict[str, Any], study: str, method: str) -> int:
    b = budgets[study]
    return int(b.get(method, max(b.values()))) if isinstance(b, dict) else int(b)


def _cell(needed: dict[str, dict[str, int | None]], budgets: dict[str, Any], study: str, method: str,
          unfinished: dict[str, set[str]] | None) -> str:
    v = needed[study].get(method, "—")
    if v == "—":
        return "—"
    text = f"> {_largest(budgets, study, method)}" if v is None else str(v)
    return f"{text} {UNFINISHED_MARK}" if unfinished and method in unfinished.get(study, ()) else text


def headline(needed: dict[str, dict[str, int | None]], budgets: dict[str, Any],
             unfinished: dict[str, set[str]] | None = None) -> str:
    """Markdown table: studies (columns) × methods (rows), the simulations each needs to reach the optimum.

    ``budgets`` gives each study's largest budget, or a mapping of each method's (see :func:`largest_budgets`).
    ``unfinished`` gives, per study, the methods with runs that stopped before their budget
    (:func:`unfinished_methods`): their cells are marked "†" and a note says why.
    """
    studies = list(needed)
    methods = list(dict.fromkeys(m for n in needed.values() for m in n))
    lines = ["| method | " + " | ".join(studies) + " |", "|---|" + "---|" * len(studies)]
    for m in methods:
        cells = [_cell(needed, budgets, st, m, unfinished) for st in studies]
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    text = "\n".join(lines) + "\n"
    if unfinished and any(unfinished.values()):
        text += (f"\n{UNFINISHED_MARK} some runs of this method on this study stopped before spending their budget; "
                 "they are not counted (see the study's compare.md).\n")
    return text


def plot_headline(needed: dict[str, dict[str, int | None]], budgets: dict[str, Any], path: Path,
                  unfinished: dict[str, set[str]] | None = None) -> Path:
    """Simulations needed per method (rows) and study (columns) as a table of colours (log scale, darker: fewer);
    "> N" in grey: not reached within the largest budget N; blank: not run on that study; "†": some runs stopped
    before their budget (``unfinished``, as for :func:`headline`)."""
    from matplotlib.colors import LogNorm

    from mechopt.report.plots import plt
    from mechopt.sim.figure_file import save_figure

    studies = list(needed)
    methods = list(dict.fromkeys(m for n in needed.values() for m in n))
    grid = np.full((len(methods), len(studies)), np.nan)
    for i, m in enumerate(methods):
        for j, st in enumerate(studies):
            v = needed[st].get(m, "—")
            if v not in ("—", None):
                grid[i, j] = float(v)
    reached = grid[np.isfinite(grid)]
    norm = LogNorm(vmin=max(1.0, reached.min() if reached.size else 1.0),
                   vmax=max(2.0, reached.max() if reached.size else 2.0))
    fig, ax = plt.subplots(figsize=(1.25 * len(studies) + 3.2, 0.42 * len(methods) + 1.8))
    ax.imshow(np.ma.masked_invalid(grid), cmap="viridis_r", norm=norm, aspect="auto")
    for i, m in enumerate(methods):
        for j, st in enumerate(studies):
            v = needed[st].get(m, "—")
            if v == "—":
                continue
            label = _cell(needed, budgets, st, m, unfinished)
            if v is None:
                ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, color="0.88"))
                ax.text(j, i, label, ha="center", va="center", fontsize=7, color="0.35")
            else:
                dark = norm(float(v)) > 0.45
                ax.text(j, i, label, ha="center", va="center", fontsize=8, fontweight="bold",
                        color="white" if dark else "black")
    ax.set_xticks(range(len(studies)))
    ax.set_xticklabels(studies, rotation=30, ha="right", fontsize=8)
    ax.set_yticks(range(len(methods)))
    ax.set_yticklabels(methods, fontsize=8)
    ax.set_title("Simulations each method needs to reach the optimum (median of the seeds; fewer is better)",
                 fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def write(runs: list[Run], truth: GroundTruth, out: Path, study: Study, seeds: int) -> tuple[Path, Path]:
    """Write compare.json, compare.md and figures/compare_gaps.png into ``out``."""
    rows = table(runs, study.problem, truth)
    out.mkdir(parents=True, exist_ok=True)
    (out / "compare.json").write_text(json.dumps({"study": study.name, "seeds": seeds, "truth": truth.__dict__,
                                                  "tolerance": tolerance(study.problem, truth),
                                                  "needed": simulations_needed(rows),
                                                  "largest_budget": largest_budgets(rows),
                                                  "unfinished_methods": sorted(unfinished_methods(rows)),
                                                  "rows": rows, "runs": [r.__dict__ for r in runs]}, indent=2))
    md = out / "compare.md"
    needed = simulations_needed(rows)
    marked = unfinished_methods(rows)
    md.write_text(markdown(rows, truth, study, seeds, runs)
                  + "\nSimulations after which the median run is within "
                  + f"{tolerance(study.problem, truth):.3g} of the optimum: "
                  + ", ".join(f"{m} {'> ' + str(largest_budgets(rows)[m]) if v is None else v}"
                              + (f" {UNFINISHED_MARK}" if m in marked else "") for m, v in needed.items()) + "\n"
                  + "\nMedian gap to the true optimum:\n\n" + pivot_markdown(rows))
    threshold = gap_pct(study.problem, truth, truth.fun + tolerance(study.problem, truth))
    fig = plot_gaps(rows, out / "figures" / "compare_gaps.png", threshold)
    return md, fig
