"""Optimizer comparison at equal simulation budgets, scored against a study's ground truth.

Every method runs through :func:`mechopt.minimize` on the same problem (the same simulator, feasibility rules and
budget of simulator calls; a study's ``[compare] engine`` may name a faster engine standing in for its own).  Its
returned design is scored by its *true* objective (the problem's batch evaluator where it has one) and by the gap to
the brute-force optimum.  The table and the figure are produced by code, from scratch and seeded:
``mechopt compare``.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError, MechoptError
from mechopt.optimize.baselines import BASELINES
from mechopt.optimize.ground_truth import GroundTruth
from mechopt.optimize.minimize import minimize
from mechopt.optimize.problem import DesignProblem
from mechopt.studies.catalogue import Study
from mechopt.surrogate.errors import SurrogateError

#: Bayesian optimisation (in-house GP, SMT's EGO) refits a Gaussian process on all samples at every step (cubic
#: cost): it is run up to this budget only, as in the literature, where it is used for small budgets.
BAYESIAN_MAX_BUDGET = 200
#: SMT's EGO refits its Kriging model with a hyperparameter search at every step (~1-2 s each at 60 points here).
EGO_MAX_BUDGET = 100


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


def compare(study: Study, truth: GroundTruth, budgets: list[int], seeds: int, methods: list[str] | None = None,
            progress=print, gp_max_budget: int | None = None) -> list[Run]:
    """Run every method at every budget and seed; returns the runs (see :func:`table`).

    ``gp_max_budget`` lowers the largest budget the Gaussian-process methods (``bayesian``, ``smt_ego``) run at:
    they refit at every call, and a run of a hundred calls takes minutes where the others take seconds.
    """
    caps = {"bayesian": BAYESIAN_MAX_BUDGET, "smt_ego": EGO_MAX_BUDGET}
    if gp_max_budget is not None:
        caps = {k: min(v, int(gp_max_budget)) for k, v in caps.items()}
    names = ["mechopt", "mechopt-global", *BASELINES]
    if methods:
        unknown = sorted(set(methods) - set(names))
        if unknown:
            raise InputError(f"unknown method {unknown[0]!r}; expected some of {', '.join(names)}")
        names = [n for n in names if n in methods]
    problem = study.problem
    runs: list[Run] = []
    for budget in budgets:
        for seed in range(seeds):
            for name in names:
                if budget > caps.get(name, budget):
                    continue
                t0 = time.perf_counter()
                try:
                    method = {"mechopt": "sparse", "mechopt-global": "sparse-global"}.get(name, name)
                    res = minimize(problem, budget=budget, method=method, seed=seed)
                    x = np.asarray(res.x) if res.success else None
                    nfev = int(res.nfev)
                except (SurrogateError, MechoptError) as exc:
                    # Too small a budget for a method is a result of the comparison, not a crash of it.
                    progress(f"  {name} at budget {budget}, seed {seed}: {exc}")
                    x, nfev = None, 0
                value = true_objective(problem, x)
                gap = gap_pct(problem, truth, value)
                runs.append(Run(name, budget, seed, None if x is None else x.tolist(), value, gap, nfev,
                                time.perf_counter() - t0))
            progress(f"  budget {budget}, seed {seed}: done ({len(runs)} runs so far)")
    return runs


def table(runs: list[Run], problem: DesignProblem | None = None, truth: GroundTruth | None = None) -> list[dict]:
    """One row per method and budget: median / best / worst true value, gap, share within 1 %, calls, time, and
    whether the median run reached the optimum (see :func:`tolerance`)."""
    tol = tolerance(problem, truth) if problem is not None and truth is not None else None
    rows = []
    for method in dict.fromkeys(r.method for r in runs):
        for budget in sorted({r.budget for r in runs if r.method == method}):
            sel = [r for r in runs if r.method == method and r.budget == budget]
            t = np.array([r.value for r in sel])
            gaps = np.array([r.gap_pct for r in sel])
            finite = np.isfinite(t)
            rows.append({
                "method": method, "budget": budget, "runs": len(sel),
                "median_value": float(np.median(t[finite])) if finite.any() else float("nan"),
                "best_value": float(np.min(t[finite])) if finite.any() else float("nan"),
                "worst_value": float(np.max(t[finite])) if finite.any() else float("nan"),
                "median_gap_pct": float(np.median(np.where(finite, gaps, np.inf))),
                "within_1pct": float(np.mean(np.where(finite, gaps, np.inf) <= 1.0)),
                "median_calls": float(np.median([r.nfev for r in sel])),
                "max_calls": int(max(r.nfev for r in sel)),
                "median_wall_s": float(np.median([r.wall_time_s for r in sel])),
                "median_reached": bool(tol is not None and finite.sum() * 2 > len(sel)
                                       and np.median(np.where(finite, t, np.inf)) <= truth.fun + tol),
            })
    return rows


def markdown(rows: list[dict], truth: GroundTruth, study: Study, seeds: int) -> str:
    """The comparison table in Markdown, with its provenance."""
    problem = study.problem
    obj = problem.objective
    engine = problem.settings().get("engine", "its own")
    lines = [f"Ground truth {obj} {truth.fun:.6g} at {problem.describe(np.array(truth.x))} (brute force, grid "
             f"{truth.step:g} + polish). Simulator: {engine}; {seeds} seeds per method and budget; every returned "
             f"design scored by its true {obj}.", "",
             f"| method | budget | runs | median {obj} | best | worst | median gap | within 1 % | calls (median / max)"
             " | wall (s) |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['method']} | {r['budget']} | {r['runs']} | {r['median_value']:.6g} | {r['best_value']:.6g}"
                     f" | {r['worst_value']:.6g} | {r['median_gap_pct']:+.2f} % | {100 * r['within_1pct']:.0f} % | "
                     f"{r['median_calls']:.0f} / {r['max_calls']} | {r['median_wall_s']:.2f} |")
    return "\n".join(lines) + "\n"


def pivot_markdown(rows: list[dict]) -> str:
    """Median gap to the true optimum per method (rows) and budget (columns), for a quick read."""
    budgets = sorted({r["budget"] for r in rows})
    lines = ["| method | " + " | ".join(f"{b} calls" for b in budgets) + " |",
             "|---|" + "---|" * len(budgets)]
    for method in dict.fromkeys(r["method"] for r in rows):
        cells = []
        for b in budgets:
            sel = [r for r in rows if r["method"] == method and r["budget"] == b]
            cells.append("—" if not sel else f"{sel[0]['median_gap_pct']:+.2f} %")
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
        g = np.array([max(r["median_gap_pct"], 1e-8) for r in sel])
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
    counted as having reached it there."""
    out: dict[str, int | None] = {}
    for method in dict.fromkeys(r["method"] for r in rows):
        by_budget = sorted((r["budget"], bool(r["median_reached"])) for r in rows if r["method"] == method)
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


def headline(needed: dict[str, dict[str, int | None]], budgets: dict[str, Any]) -> str:
    """Markdown table: studies (columns) × methods (rows), the simulations each needs to reach the optimum.

    ``budgets`` gives each study's largest budget, or a mapping of each method's (see :func:`largest_budgets`).
    """
    studies = list(needed)
    methods = list(dict.fromkeys(m for n in needed.values() for m in n))
    lines = ["| method | " + " | ".join(studies) + " |", "|---|" + "---|" * len(studies)]
    for m in methods:
        cells = []
        for st in studies:
            v = needed[st].get(m, "—")
            cells.append("—" if v == "—" else (f"> {_largest(budgets, st, m)}" if v is None else str(v)))
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot_headline(needed: dict[str, dict[str, int | None]], budgets: dict[str, Any], path: Path) -> Path:
    """Simulations needed per method (rows) and study (columns) as a table of colours (log scale, darker: fewer);
    "> N" in grey: not reached within the largest budget N; blank: not run on that study."""
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
            if v is None:
                ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, color="0.88"))
                ax.text(j, i, f"> {_largest(budgets, st, m)}", ha="center", va="center", fontsize=7, color="0.35")
            else:
                dark = norm(float(v)) > 0.45
                ax.text(j, i, str(v), ha="center", va="center", fontsize=8, fontweight="bold",
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
                                                  "largest_budget": largest_budgets(rows), "rows": rows,
                                                  "runs": [r.__dict__ for r in runs]}, indent=2))
    md = out / "compare.md"
    needed = simulations_needed(rows)
    md.write_text(markdown(rows, truth, study, seeds)
                  + "\nSimulations after which the median run is within "
                  + f"{tolerance(study.problem, truth):.3g} of the optimum: "
                  + ", ".join(f"{m} {'> ' + str(largest_budgets(rows)[m]) if v is None else v}"
                              for m, v in needed.items()) + "\n"
                  + "\nMedian gap to the true optimum:\n\n" + pivot_markdown(rows))
    threshold = gap_pct(study.problem, truth, truth.fun + tolerance(study.problem, truth))
    fig = plot_gaps(rows, out / "figures" / "compare_gaps.png", threshold)
    return md, fig
