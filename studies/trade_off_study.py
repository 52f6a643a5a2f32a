"""A study with several objectives or limits on simulated outputs, run whole: optimise with the default method,
simulate the study's reference designs, write the report (:mod:`mechopt.report.front`).

DIR receives ``result.json``, ``report.md``, ``front.csv`` (several objectives), ``figures/front.png`` and
``figures/progress.png`` (hypervolume against simulations), and the sample store ``samples.sqlite`` by default.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import MechoptError
from mechopt.optimize.minimize import minimize
from mechopt.report.front import front_csv, front_figure, front_table, progress_figure

__all__ = ["DEFAULT_TRADE_OFF_BUDGET", "TradeOffStudy", "run_trade_off_study"]

#: Simulations of a trade-off study when neither the command line nor the study says.
DEFAULT_TRADE_OFF_BUDGET = 150


@dataclass
class TradeOffStudy:
    """What a trade-off study run produced.

    Attributes
    ----------
    result : OptimizeResult
        The default method's result.
    references : dict
        Outputs of the study's reference designs (name -> outputs; an empty dict where the design failed).
    out : Path
        The output folder.
    """

    result: Any
    references: dict[str, dict[str, float]]
    out: Path


def _references(study: Any) -> dict[str, dict[str, float]]:
    """The study's named designs simulated (the paper's), outputs by name; {} where a design cannot move."""
    problem = study.problem
    refs = {}
    for name, entry in study.designs.items():
        x = np.array([entry[v] for v in problem.names], dtype=float)
        try:
            refs[name] = {k: v for k, v in problem.evaluate(x).items() if isinstance(v, int | float)}
        except MechoptError:
            refs[name] = {}
    return refs


def run_trade_off_study(study: Any, out: Path, budget: int, seed: int = 0, workers: int | None = 1,
                        store: str | Path | None = None, progress: bool = False) -> TradeOffStudy:
    """Optimise a trade-off study and write its report into ``out``.

    Parameters
    ----------
    study : Study
        A loaded study whose problem has several objectives or limits.
    out : Path
        Output folder (made if missing).
    budget : int
        Simulations.
    seed : int
        Seed of the method.
    workers : int, optional
        Local worker processes (None: every core).
    store : path, optional
        Sample store (default ``out/samples.sqlite``).
    progress : bool
        Progress bars.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    result = minimize(study.problem, budget, seed=seed, workers=workers, store=store or out / "samples.sqlite",
                      progress=progress)
    refs = _references(study)
    _write(study, result, refs, out)
    return TradeOffStudy(result, refs, out)


def _write(study: Any, result: Any, refs: dict[str, dict[str, float]], out: Path) -> None:
    problem = study.problem
    spec = problem.objective_spec
    figures = out / "figures"
    front_figure(problem, result, figures / "front.png", refs)
    if spec.k > 1:
        progress_figure(problem, result, figures / "progress.png")
        front_csv(problem, result, out / "front.csv")
    names = list(dict.fromkeys([*spec.names, *problem.limit_spec.names]))
    lines = [f"# {study.name}: {', '.join(spec.labels)}" + (f" under {problem.limit_spec.describe()}"
                                                           if problem.limit_spec.m else ""),
             "", study.description, "", f"{result.message}", "",
             f"Simulations: {result.nfev} ({result.nnew} new, {result.nreused} reused, {result.nfailed} failed).", ""]
    if spec.k > 1:
        lines += [f"Hypervolume {result.get('hypervolume', float('nan')):.4g}; normalisation: "
                  f"{result.get('normalisation', '')}.", "", "## Front (sorted by the first objective)", ""]
    else:
        lines += ["## Answer" + ("" if result.success else " (infeasible: the closest design)"), ""]
    lines += front_table(problem, result)
    lines += ["", "## Reference designs", "", "| design | " + " | ".join(problem.output_label(n) for n in names)
              + " |", "|---|" + "---|" * len(names)]
    for name, o in refs.items():
        lines.append(f"| {name} | " + " | ".join(f"{o.get(n, float('nan')):.4g}" for n in names) + " |")
    lines += ["", "![front](figures/front.png)", ""]
    if spec.k > 1:
        lines += ["![hypervolume](figures/progress.png)", "", "The front as CSV: [front.csv](front.csv).", ""]
    (out / "report.md").write_text("\n".join(lines))
    summary = {"study": study.name, "objective": list(spec.labels), "limits": problem.limit_spec.describe(),
               "success": bool(result.success), "message": result.message, "nfev": int(result.nfev),
               "x": np.asarray(result.x).tolist(), "fun": np.asarray(result.fun).tolist(),
               "front_outputs": result.front_outputs, "hypervolume": result.get("hypervolume"),
               "reference_point": np.asarray(result.get("reference_point", [])).tolist(),
               "normalisation": result.get("normalisation"), "references": refs,
               "variables": list(problem.names)}
    (out / "result.json").write_text(json.dumps(summary, indent=1, default=float))
