"""Brute-force benchmark study: the ventilator's true optimum by a dense grid of the analytic engine.

Run: ``python -m benchmarks.bench_bruteforce [--steps 2,1,0.5]``.  For each grid spacing it prints the designs
evaluated, the best grid point, the polished optimum and the time; numba is warmed up first.
"""

from __future__ import annotations

import argparse
import os
import time

from mechopt.optimize.ground_truth import compute_ground_truth
from mechopt.sim.four_bar.analytic import analytic_batch
from mechopt.studies.catalogue import load_study


def main() -> None:
    """Run the brute force at each spacing and print a Markdown table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--steps", default="2,1,0.5", help="grid spacings in mm, comma separated")
    parser.add_argument("--study", default="ventilator")
    parser.add_argument("--starts", type=int, default=30, help="random feasible starts of the basin check")
    args = parser.parse_args()
    study = load_study(args.study, {"engine": "analytic"})
    analytic_batch(study.problem.bounds[:, 0][None, :] + 1.0, study.problem.mechanism)  # warm-up
    print(f"study {study.name}, region {study.problem.bounds.tolist()} mm, {os.cpu_count()} cores")
    print()
    print("| grid (mm) | designs | feasible | best grid design (mm) | T_RMS grid (N·m) | polished optimum (mm) "
          "| T_RMS (N·m) | designs/s | time (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for step in (float(s) for s in args.steps.split(",")):
        t0 = time.perf_counter()
        g = compute_ground_truth(study.problem, step)
        wall = time.perf_counter() - t0
        fmt = lambda v: "(" + ", ".join(f"{c:.3f}" for c in v) + ")"  # noqa: E731
        print(f"| {step:g} | {g.n_evaluated:,} | {g.n_feasible:,} | {fmt(g.grid_x)} | {g.grid_fun:.5f} | "
              f"{fmt(g.x)} | {g.fun:.6f} | {g.n_evaluated / wall:,.0f} | {wall:.1f} |")


    print()
    print(basin_check(study, args.starts))


def basin_check(study, n_starts: int, seed: int = 5) -> str:
    """Run SLSQP on the analytic engine from random feasible starts and count the distinct optima it ends at."""
    from collections import Counter

    import numpy as np

    from mechopt.optimize.ground_truth import polish
    from mechopt.sim.four_bar.feasibility import feasible_mask

    rng = np.random.default_rng(seed)
    box = study.problem.bounds
    starts = rng.uniform(box[:, 0], box[:, 1], size=(100 * n_starts, 3))
    starts = starts[feasible_mask(starts, study.problem.mechanism)][:n_starts]
    ends = Counter(round(polish(study.problem, x0)[1], 4) for x0 in starts)
    found = ", ".join(f"{f:.4f} N·m ×{n}" for f, n in sorted(ends.items()))
    return f"basin check: SLSQP from {len(starts)} random feasible starts ends at {found}"


if __name__ == "__main__":
    main()
