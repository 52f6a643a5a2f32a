"""What a trade-off run leaves for a person: the front figure, hypervolume against simulations, front.csv, report.md.

The front figure shows the outputs themselves (a maximised objective as its own value, not negated): every simulated
design, the infeasible ones (a broken margin or limit) marked, the front as a staircase, and named reference
designs (a paper's) placed on it.  Three or four objectives: one panel per pair of objectives.
"""

from __future__ import annotations

import csv
import itertools
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from mechopt.optimize.problem import DesignProblem  # noqa: E402

__all__ = ["front_csv", "front_figure", "front_table", "progress_figure"]


def _outputs_of(problem: DesignProblem, F: np.ndarray) -> np.ndarray:
    """Minimised objectives (n, k) back to the outputs' own values."""
    return np.atleast_2d(F) * np.asarray(problem.objective_spec.senses)


def front_figure(problem: DesignProblem, result: Any, path: Path,
                 references: Mapping[str, Mapping[str, float]] | None = None) -> Path:
    """The front over every simulated design, infeasible ones marked, reference designs placed (PNG).

    Parameters
    ----------
    problem : DesignProblem
        Its objectives name the axes.
    result : OptimizeResult
        A trade-off result (``simulated``, ``fun``).
    path : Path
        PNG written.
    references : mapping, optional
        ``{name: outputs}`` of designs to place on the figure.
    """
    spec = problem.objective_spec
    sim = result.simulated
    ok = np.asarray(sim["ok"], bool)
    feasible = np.asarray(sim["feasible"], bool)
    Y = _outputs_of(problem, sim["F"])
    front = _outputs_of(problem, np.atleast_2d(result.fun).reshape(-1, spec.k)) if result.success \
        else np.zeros((0, spec.k))
    names = list(spec.names)
    if spec.k == 1:
        # One objective under limits: the objective against the first limited output, the answer as the "front".
        names.append(problem.limit_spec.names[0])
        Y = np.column_stack([Y, np.asarray(sim["G"])[:, 0]])
        front = np.array([[result.outputs[n] for n in names]]) if result.success else np.zeros((0, 2))
    pairs = list(itertools.combinations(range(len(names)), 2))
    fig, axes = plt.subplots(1, len(pairs), figsize=(6.4 * len(pairs), 4.8), squeeze=False)
    for ax, (i, j) in zip(axes[0], pairs, strict=True):
        ax.scatter(Y[ok & feasible, i], Y[ok & feasible, j], s=14, c="0.55", label="simulated, feasible")
        bad = ok & ~feasible
        if bad.any():
            ax.scatter(Y[bad, i], Y[bad, j], s=18, marker="x", c="tab:red", label="simulated, breaks a margin/limit")
        if front.shape[0]:
            order = np.argsort(front[:, i])
            if len(names) == 2 and spec.k == 2:
                ax.step(front[order, i], front[order, j], where="post", c="tab:blue", lw=1.2)
            ax.scatter(front[:, i], front[:, j], s=28, c="tab:blue", zorder=3,
                       label="Pareto front" if spec.k > 1 else "answer")
        for (name, out), marker in zip((references or {}).items(), "s^Dv<>p", strict=False):
            vi, vj = out.get(names[i]), out.get(names[j])
            if vi is not None and vj is not None:
                ax.scatter([vi], [vj], marker=marker, s=60, facecolors="none", edgecolors="k", zorder=4)
                ax.annotate(name.replace("_", " "), (vi, vj), textcoords="offset points", xytext=(6, 4), fontsize=8)
        ax.set_xlabel(_axis(problem, names[i]))
        ax.set_ylabel(_axis(problem, names[j]))
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8, loc="best")
    what = "Pareto front" if spec.k > 1 else f"best {spec.labels[0]} under {problem.limit_spec.describe()}"
    fig.suptitle(f"{problem.name}: {what}, {ok.sum()} simulated designs")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _axis(problem: DesignProblem, name: str) -> str:
    spec = problem.objective_spec
    if name not in spec.names:
        return f"{problem.output_label(name)}, limited"
    sense = "maximised" if spec.senses[spec.names.index(name)] < 0 else "minimised"
    return f"{problem.output_label(name)}, {sense}"


def progress_figure(problem: DesignProblem, result: Any, path: Path) -> Path:
    """Hypervolume of the feasible front against simulations (PNG)."""
    trace = np.asarray(result.get("hypervolume_trace", []), dtype=float)
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    ax.plot(np.arange(1, trace.size + 1), trace, c="tab:blue")
    ax.set_xlabel("simulations")
    ax.set_ylabel("hypervolume (normalised)")
    ax.set_title(f"{problem.name}: hypervolume of the feasible front")
    ax.grid(alpha=0.3)
    fig.text(0.01, 0.01, str(result.get("normalisation", "")), fontsize=6, wrap=True)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _columns(problem: DesignProblem, result: Any) -> list[str]:
    outs = list(problem.outputs)
    extra = sorted({k for o in result.front_outputs for k, v in o.items()
                    if k not in outs and isinstance(v, int | float) and not isinstance(v, bool)})
    return outs + extra


def front_csv(problem: DesignProblem, result: Any, path: Path) -> Path:
    """One row per front design: the variables and every numeric output, with units in the header."""
    outs = _columns(problem, result)
    header = [f"{v.name} ({v.unit})" if v.unit else v.name for v in problem.variables]
    header += [problem.output_label(o) for o in outs]
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for x, o in zip(np.atleast_2d(result.x), result.front_outputs, strict=True):
            w.writerow([f"{v:.6g}" for v in x] + [f"{float(o.get(n, np.nan)):.6g}" for n in outs])
    return path


def front_table(problem: DesignProblem, result: Any) -> list[str]:
    """The front as Markdown table lines (variables, then the objectives and limited outputs)."""
    names = list(dict.fromkeys([*problem.objective_spec.names, *problem.limit_spec.names]))
    head = [v.axis_label for v in problem.variables] + [problem.output_label(n) for n in names]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for x, o in zip(np.atleast_2d(result.x), result.front_outputs, strict=True):
        cells = [f"{v:.4g}" for v in x] + [f"{float(o.get(n, np.nan)):.4g}" for n in names]
        lines.append("| " + " | ".join(cells) + " |")
    return lines
