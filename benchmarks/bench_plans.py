"""Benchmark of line plans: held-out accuracy of the global model for the paper's plan and for mechopt's.

Run with ``python -m benchmarks.bench_plans [--seeds 5] [--engine analytic]``.  Every configuration samples its lines,
fits and blends them, and is scored on 10 held-out lines of 30 points inside its hull (the study's validation), with
the analytic engine by default (the pymunk engine gives the same figures to ~1e-4 and takes 15 times longer).  Prints a
Markdown table: samples on the lines, coverage of the feasible region, held-out RMSE in N·m and in per cent of the
ground truth's T_min, and the Lebesgue constant of the blend over the validation points (how much it amplifies the
line models' errors).
"""

from __future__ import annotations

import argparse
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from mechopt.optimize.ground_truth import load_or_compute
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.optimize.sparse.stage import build_stage
from mechopt.optimize.sparse.validate import validate
from mechopt.runs.store import SampleStore
from mechopt.studies.catalogue import load_study
from mechopt.studies.runner import study_options

#: (label, options changed from the study's defaults, the toggle relaxation of the lines in degrees)
CONFIGS = [
    ("the paper's: 7 lines, its Δ, spacing and origin, T_RMS fitted", dict(plan="paper", fit="value"), 5.0),
    ("7 lines on the region's outline, T_RMS fitted", dict(n_lines=7, samples_per_line=40, min_samples=24,
                                                            layout="boundary", fit="value"), 10.0),
    ("7 lines on the region's outline, T_RMS² fitted", dict(n_lines=7, samples_per_line=40, min_samples=24,
                                                             layout="boundary"), 10.0),
    ("21 lines on the region's outline, T_RMS² fitted", dict(layout="boundary"), 5.0),
    ("21 lines at Fekete nodes, T_RMS fitted", dict(fit="value"), 5.0),
    ("21 lines at Fekete nodes, T_RMS² fitted (default)", dict(), 5.0),
]


def lebesgue_constant(model, designs: np.ndarray) -> float:
    """max Σ|L_i| of the blend over the designs (mm)."""
    P = model.plan.normal_coordinates(model.to_u(designs))
    return float(np.abs(model.model.blend.lagrange(P)).sum(axis=1).max())


def main(argv: list[str] | None = None) -> None:
    """Print the table (see the module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5, help="seeds of the planner and the validation lines")
    parser.add_argument("--engine", choices=("analytic", "pymunk"), default="analytic")
    args = parser.parse_args(argv)
    study = load_study("ventilator", {"engine": args.engine})
    base = study_options(study)
    with tempfile.TemporaryDirectory() as tmp:
        truth = load_or_compute(study.problem, Path(tmp) / "truth.json", 1.0)
        print(f"study ventilator, {args.engine} engine, T_min {truth.fun:.4f} N·m (ground truth); "
              f"seeds 0..{args.seeds - 1}; 10 held-out lines x 30 points\n")
        print("| plan | samples (median) | coverage (median) | held-out RMSE (N·m), median | % of T_min: median "
              "(min–max) | Lebesgue constant (median) |")
        print("|---|---|---|---|---|---|")
        for label, changes, relax in CONFIGS:
            rows = []
            space = ModelSpace(replace(study.problem, toggle_relax_deg=relax))
            for seed in range(args.seeds):
                options = base.replace(**changes, seed=seed, search_points=200_000)
                with SampleStore(Path(tmp) / f"s{seed}.sqlite") as store:
                    sampler = Sampler(space.problem, store, progress=False)
                    stage = build_stage("global", space, options, sampler, options.n_lines,
                                        options.samples_per_line, options.search_points,
                                        paper=options.plan == "paper", max_samples=options.budget - 1)
                    val = validate(stage.model, space, sampler, options.validation_lines,
                                   options.validation_points, seed, f_min=truth.fun)
                designs = np.vstack([np.asarray(line["designs"]) for line in val.lines])
                rows.append((stage.n_samples, stage.coverage, val.rmse, lebesgue_constant(stage.model, designs)))
            r = np.array(rows)
            pct = 100 * r[:, 2] / truth.fun
            print(f"| {label} | {np.median(r[:, 0]):.0f} | {np.median(r[:, 1]):.0%} | {np.median(r[:, 2]):.4f} | "
                  f"{np.median(pct):.2f} ({pct.min():.2f}–{pct.max():.2f}) | {np.median(r[:, 3]):.1f} |", flush=True)


if __name__ == "__main__":
    main()
