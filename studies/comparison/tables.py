"""The tables of an optimizer comparison: one row per method and budget, the pivot of median gaps, the simulations
each method needs to reach the optimum, and the files ``mechopt compare`` writes.

Every table states its measure in its header: the gap is a percentage whose base the header names (the function's
range over the box, or the optimum; :func:`~mechopt.studies.comparison.score.gap_measure`), beside the true values
f of the returned designs and the optimum f*.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.optimize.ground_truth import GroundTruth
from mechopt.optimize.problem import DesignProblem
from mechopt.studies.catalogue import Study
from mechopt.studies.comparison.engine import Run
from mechopt.studies.comparison.score import gap_basis, gap_measure, gap_pct, tolerance

__all__ = ["UNFINISHED_MARK", "headline", "largest_budgets", "markdown", "pivot_markdown", "simulations_needed",
           "cell_text", "table", "unfinished_methods", "unfinished_runs", "write", "write_headline"]

#: The mark of an unfinished run in the tables.
UNFINISHED_MARK = "†"

#: Where the optimum a comparison is scored against comes from, by :attr:`GroundTruth.key`.
_SOURCES = {"known": "declared by the problem", "declared": "the study's [compare] known_optimum, simulated here"}


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


def _source(truth: GroundTruth) -> str:
    return _SOURCES.get(truth.key, f"brute force, grid {truth.step:g} + polish")


def markdown(rows: list[dict], truth: GroundTruth, study: Study, seeds: int, runs: list[Run] | None = None) -> str:
    """The comparison table in Markdown, with its provenance, its measure and (given ``runs``) a note per unfinished
    run: the true values f of the returned designs and the optimum f* stand beside the gap."""
    problem = study.problem
    obj = problem.objective
    engine = problem.settings().get("engine", "its own")
    measure = gap_measure(problem, truth)
    lines = [f"Optimum {obj}* = {truth.fun:.6g} at {problem.describe(np.array(truth.x))} ({_source(truth)}). "
             f"Simulator: {engine}; {seeds} seeds per method and budget; every returned design scored by its true "
             f"{obj}. Gap: {measure}.", "",
             f"| method | budget | runs | median {obj} | best {obj} | worst {obj} | {obj}* | median gap "
             f"({gap_basis(problem, truth)}) "
             f"| gap within 1 % | calls (median / max) | wall (s) | stopped early {UNFINISHED_MARK} |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        unfinished = r.get("unfinished", 0)
        stopped = f"{unfinished} {UNFINISHED_MARK}" if unfinished else "0"
        if unfinished == r["runs"]:  # no finished run: nothing to report but the calls
            scores = f"— | — | — | {truth.fun:.6g} | — | —"
        else:
            scores = (f"{r['median_value']:.6g} | {r['best_value']:.6g} | {r['worst_value']:.6g} | {truth.fun:.6g} | "
                      f"{r['median_gap_pct']:+.2f} % | {100 * r['within_1pct']:.0f} %")
        lines.append(f"| {r['method']} | {r['budget']} | {r['runs']} | {scores} | {r['median_calls']:.0f} / "
                     f"{r['max_calls']} | {r['median_wall_s']:.2f} | {stopped} |")
    return "\n".join(lines) + "\n" + (_notes(runs) if runs else "")


def pivot_markdown(rows: list[dict], problem: DesignProblem | None = None, truth: GroundTruth | None = None) -> str:
    """Median gap to the true optimum per method (rows) and budget (columns), for a quick read, each with the
    median f it stands for; given ``problem`` and ``truth``, a first line states f* and the gap's measure.  "†":
    some runs of that cell stopped before their budget and are left out of its median."""
    budgets = sorted({r["budget"] for r in rows})
    head = []
    if problem is not None and truth is not None:
        head = [f"Median gap to the optimum {problem.objective}* = {truth.fun:.6g} ({gap_measure(problem, truth)}), "
                f"and the median {problem.objective} in brackets:", ""]
    lines = [*head, "| method | " + " | ".join(f"{b} calls" for b in budgets) + " |",
             "|---|" + "---|" * len(budgets)]
    for method in dict.fromkeys(r["method"] for r in rows):
        cells = []
        for b in budgets:
            sel = [r for r in rows if r["method"] == method and r["budget"] == b]
            if not sel:
                cells.append("—")
                continue
            gap = f"{sel[0]['median_gap_pct']:+.2f} % (f {sel[0]['median_value']:.4g})"
            if sel[0].get("complete", True):
                cells.append(gap)
            elif sel[0].get("unfinished", 0) < sel[0]["runs"]:
                cells.append(f"{gap} {UNFINISHED_MARK}")
            else:
                cells.append(f"— {UNFINISHED_MARK}")
        lines.append(f"| {method} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


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


def cell_text(needed: dict[str, dict[str, int | None]], budgets: dict[str, Any], study: str, method: str,
              unfinished: dict[str, set[str]] | None) -> str:
    """One cell of the headline: the simulations ``method`` needs on ``study``, "> N" when not reached within its
    largest budget N, "—" when not run there, marked "†" when some of its runs stopped before their budget."""
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
    lines = ["Simulations after which the median run is within the tolerance of the optimum f* (0.5 % of the range "
             "of f over the box where the problem declares it, else 0.5 % of f*); \"> N\": not within N:", "",
             "| method | " + " | ".join(studies) + " |",
             "|---|" + "---|" * len(studies)]
    for m in methods:
        cells = [cell_text(needed, budgets, st, m, unfinished) for st in studies]
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    text = "\n".join(lines) + "\n"
    if unfinished and any(unfinished.values()):
        text += (f"\n{UNFINISHED_MARK} some runs of this method on this study stopped before spending their budget; "
                 "they are not counted (see the study's compare.md).\n")
    return text


def write(runs: list[Run], truth: GroundTruth, out: Path, study: Study, seeds: int) -> tuple[Path, Path]:
    """Write compare.json, compare.md and figures/compare_gaps.png into ``out``."""
    from mechopt.report.comparison_figures import plot_gaps

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
                  + "\n" + pivot_markdown(rows, study.problem, truth))
    threshold = gap_pct(study.problem, truth, truth.fun + tolerance(study.problem, truth))
    fig = plot_gaps(rows, out / "figures" / "compare_gaps.png", threshold, gap_measure(study.problem, truth))
    return md, fig


def write_headline(needed: dict[str, dict[str, int | None]], budgets: dict[str, Any], out: Path,
                   unfinished: dict[str, set[str]] | None = None) -> tuple[str, Path, Path]:
    """Write headline.md and figures/compare_headline.png of a comparison on several studies into ``out``.

    Returns
    -------
    text : str
        The table (:func:`headline`).
    md, fig : Path
        The files written.
    """
    from mechopt.report.comparison_figures import plot_headline

    text = headline(needed, budgets, unfinished)
    md = out / "headline.md"
    md.write_text(text)
    return text, md, plot_headline(needed, budgets, out / "figures" / "compare_headline.png", unfinished)
