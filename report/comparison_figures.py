"""The figures of an optimizer comparison: the median gap against the budget, and the simulations each method needs
on each study as a table of colours."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from mechopt.report.plots import plt
from mechopt.sim.figure_file import save_figure
from mechopt.studies.comparison.engine import OWN_METHOD
from mechopt.studies.comparison.tables import cell_text

__all__ = ["plot_gaps", "plot_headline"]


def plot_gaps(rows: list[dict], path: Path, threshold_pct: float = 0.5,
              measure: str = "%, or 100 f where f* = 0") -> Path:
    """Median gap to the ground truth against the number of simulations, log scales, one curve per method;
    ``threshold_pct`` is the gap that counts as reaching the optimum (the comparison's tolerance, in the gap's
    units); ``measure`` says what the gap is a percentage of (the axis label)."""
    fig, ax = plt.subplots(figsize=(10, 5.2))
    for i, method in enumerate(dict.fromkeys(r["method"] for r in rows)):
        sel = [r for r in rows if r["method"] == method]
        b = np.array([r["budget"] for r in sel])
        # An unfinished cell is not a finished comparison: a gap in the curve, not a point.
        g = np.array([max(r["median_gap_pct"], 1e-8) if r.get("complete", True) else np.nan for r in sel])
        style = dict(lw=3, color="k", marker="o") if method == OWN_METHOD else dict(lw=1.3, marker=".")
        ax.plot(b, np.where(np.isfinite(g), g, np.nan), label=method, color=None if method != OWN_METHOD else "k",
                linestyle="-" if i < 10 else "--", **{k: v for k, v in style.items() if k != "color"})
    ax.axhline(threshold_pct, color="C3", ls=":", lw=1, label="reached: within the tolerance of the optimum")
    ax.set_xscale("log")
    ax.set_yscale("log")
    budgets = sorted({int(r["budget"]) for r in rows})
    ax.set_xticks(budgets)
    ax.set_xticklabels([str(b) for b in budgets])
    ax.minorticks_off()
    ax.set_xlabel("simulator calls (budget)")
    ax.set_ylabel(f"median gap to the optimum\n({measure}; floor 1e-8)", fontsize=8)
    ax.set_title("Optimizers at equal simulation budgets (median over seeds)", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    return save_figure(fig, path)


def plot_headline(needed: dict[str, dict[str, int | None]], budgets: dict[str, Any], path: Path,
                  unfinished: dict[str, set[str]] | None = None) -> Path:
    """Simulations needed per method (rows) and study (columns) as a table of colours (log scale, darker: fewer);
    "> N" in grey: not reached within the largest budget N; blank: not run on that study; "†": some runs stopped
    before their budget (``unfinished``, as for :func:`mechopt.studies.comparison.tables.headline`)."""
    from matplotlib.colors import LogNorm

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
            label = cell_text(needed, budgets, st, m, unfinished)
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
