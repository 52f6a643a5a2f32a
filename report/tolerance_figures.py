"""Figures of the tolerance analyses: the objective's distribution over a design's scatter with each margin's
probability of violation, and the Sobol indices as bars."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from mechopt.optimize.problem import DesignProblem  # noqa: E402
from mechopt.sim.figure_file import figure_path, save_figure  # noqa: E402

__all__ = ["plot_sobol", "plot_tolerance"]


def plot_tolerance(problem: DesignProblem, analysis, path: str | Path) -> Path:
    """The objective's histogram over the scatter (5/50/95 % quantiles, confirmations) and each margin's probability
    of violation, for a :class:`~mechopt.optimize.analysis.tolerance.ToleranceResult`; returns the PNG written."""
    path = figure_path(path)
    s = analysis.statistics
    unit = problem.output_units.get(problem.objective, "")
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [3, 2]})
    ax.hist(s.values, bins=60, color="tab:blue", alpha=0.75, label=f"model, {s.values.size} scattered designs")
    top = ax.get_ylim()[1] * 1.3  # headroom: the legend above the bars, the quantiles' labels below it
    ax.set_ylim(0.0, top)
    for level, value in s.quantiles.items():
        ax.axvline(value, color="k", ls="--", lw=1)
        ax.text(value, top * 0.78, f" {100 * level:g} %", va="top", fontsize=8)
    sims = [c["simulated"] for c in analysis.confirmations if np.isfinite(c["simulated"])]
    if sims:
        ax.plot(sims, np.zeros(len(sims)), "rv", ms=9, clip_on=False, label="simulated at the quantiles")
    ax.set_xlabel(f"{problem.objective} ({unit})" if unit else problem.objective)
    ax.set_ylabel("scattered designs")
    ax.set_title(f"{problem.objective} over the scatter: mean {s.mean:.4g} {unit}")
    ax.legend(fontsize=8, loc="upper left")
    names = [*problem.constraints, "any"]
    p = [s.violation[c] for c in names]
    err = [2.0 * s.standard_error[c] for c in names]
    bx.barh(names, p, xerr=err, color=["tab:red" if v > 0 else "tab:green" for v in p], capsize=3)
    for i, v in enumerate(p):
        bx.text(v, i, f" {v:.3f}", va="center", fontsize=8)
    bx.set_xlim(0.0, max(1.0, max(p) * 1.15))
    bx.set_xlabel("probability of violation (±2 standard errors)")
    bx.set_title("margins violated over the scatter")
    fig.suptitle(f"Tolerance analysis of {problem.describe(analysis.design)}: "
                 f"{analysis.tolerances.describe(problem)}", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_sobol(sensitivity, path: str | Path, objective: str = "objective") -> Path:
    """First-order and total Sobol indices of each variable as bars, for a
    :class:`~mechopt.optimize.analysis.sensitivity.Sensitivity`; returns the PNG written."""
    path = figure_path(path)
    x = np.arange(len(sensitivity.names))
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.bar(x - 0.18, sensitivity.first_order, 0.36, label="first order", color="tab:blue")
    ax.bar(x + 0.18, sensitivity.total_order, 0.36, label="total", color="tab:orange")
    for xi, f, t in zip(x, sensitivity.first_order, sensitivity.total_order, strict=True):
        ax.text(xi - 0.18, f, f"{f:.2f}", ha="center", va="bottom", fontsize=8)
        ax.text(xi + 0.18, t, f"{t:.2f}", ha="center", va="bottom", fontsize=8)
    ax.set_xticks(x, sensitivity.names)
    ax.set_ylim(0.0, 1.05)
    ax.set_xlabel("design variable")
    ax.set_ylabel("share of the variance")
    ax.set_title(f"Sobol indices of {objective} over the region "
                 f"({100 * sensitivity.infeasible_share:.0f} % infeasible)", fontsize=10)
    ax.legend()
    fig.tight_layout()
    return save_figure(fig, path)
