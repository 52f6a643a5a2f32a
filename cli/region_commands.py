"""Commands on a study's design region: ``mechopt feasible`` (the feasible region drawn, with every reference
design's margins) and ``mechopt truth`` (the true optimum by brute force of a fast batch evaluator)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from mechopt.cli.arguments import positive_float
from mechopt.cli.simulate_command import feasibility_message
from mechopt.cli.study_arguments import add_study_argument, load
from mechopt.errors import InputError

__all__ = ["add_parsers", "run_feasible", "run_truth"]


def add_parsers(sub, engines: tuple[str, ...]) -> None:
    """Add ``truth`` and ``feasible`` to the subcommands."""
    p = sub.add_parser("truth", help="brute-force a study's true optimum (a fast batch evaluator), cached")
    add_study_argument(p, engines)
    p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
    p.add_argument("--truth-grid", type=positive_float, default=1.0, help="grid step (the variables' unit)")
    p.set_defaults(func=run_truth)

    p = sub.add_parser("feasible", help="plot the feasible region with every reference design")
    add_study_argument(p, engines)
    p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
    p.set_defaults(func=run_feasible)


def _marks(study, out: Path) -> dict[str, np.ndarray]:
    """The study's reference designs, and the optimum of an earlier run in ``out`` if there is one."""
    marks = study.reference_designs()
    result = out / "result.json"
    if result.is_file():
        try:
            d = json.loads(result.read_text())["optimum"]["design"]
            marks["optimum"] = np.array([d[n] for n in study.problem.names])
        except (OSError, ValueError, KeyError, TypeError):
            raise InputError(f"{result} is damaged (not a mechopt result); rerun `mechopt study {study.name}`") \
                from None
    return marks


def run_feasible(args: argparse.Namespace, rest: list[str]) -> int:
    """Draw the feasible region (slices; the 3-D view for 3 variables) and print each design's margins."""
    from mechopt.report.plots import plot_feasible_3d, plot_feasible_slices
    from mechopt.studies.runner import check_output_folder

    study = load(args)
    problem = study.problem
    if not problem.constraints:
        # A figure of a box that is feasible everywhere would be one flat colour.
        print(f"{study.name!r} declares no constraints: every design in its box is feasible; no figure drawn")
        return 0
    out = check_output_folder(Path(args.out or f"{study.name}-study"))
    marks = _marks(study, out)
    files = [plot_feasible_slices(problem, out / "figures" / "feasible_slices_all_designs.png", marks=marks,
                                  n_slices=5)]
    if problem.dim == 3:
        files.append(plot_feasible_3d(problem, out / "figures" / "feasible_3d_all_designs.png", marks=marks))
    rng = np.random.default_rng(0)
    cloud = rng.uniform(problem.bounds[:, 0], problem.bounds[:, 1], size=(200_000, problem.dim))
    print(f"{100 * problem.feasible(cloud).mean():.1f} % of the region is feasible")
    for name, x in marks.items():
        margins = dict(zip(problem.constraints, problem.constraint_margins(x[None, :])[0].tolist(), strict=True))
        print(feasibility_message(problem, x, margins, bool(problem.feasible(x)[0])).replace("design", name, 1))
    print("figures written to " + " and ".join(map(str, files)))
    return 0


def run_truth(args: argparse.Namespace, rest: list[str]) -> int:
    """Brute-force the study's optimum (cached in the output folder) and print it."""
    from mechopt.optimize.ground_truth import batch_evaluator, load_or_compute
    from mechopt.studies.runner import check_output_folder

    study = load(args)
    batch_evaluator(study.problem)  # refused before the output folder is made
    out = check_output_folder(Path(args.out or f"{study.name}-study"))
    truth = load_or_compute(study.problem, out / f"ground_truth_{args.truth_grid:g}.json", args.truth_grid)
    print(f"ground truth of {study.name}: {study.problem.describe(np.array(truth.x))}, {study.problem.objective} "
          f"{truth.fun:.6g} ({truth.n_feasible} feasible of {truth.n_evaluated} grid designs, "
          f"{truth.wall_time_s:.1f} s; cached in {out})")
    return 0
