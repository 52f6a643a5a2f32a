"""The ventilator's trade-offs against a brute force over the analytic engine.

1. Two objectives, T_RMS (minimised) against the toggle margin (deg, maximised), from ``--budget-front``
   simulations: the hypervolume of the run's front (its designs re-simulated) over that of the brute-force front.
   Normalisation: z = (f − ideal) / (nadir − ideal) with the ideal and nadir of the brute-force front, reference
   point z = 1.1 in both objectives.
2. One objective under a simulated limit: the largest toggle margin with T_RMS <= ``--limit`` N·m from
   ``--budget-limit`` simulations, against the brute force's largest, and whether the answer meets the limit when
   re-simulated.

The brute force is a grid of ``--step`` mm over the box, every design that satisfies the study's margins (the
15° toggle margin among them) simulated by the analytic engine (numba).

Run, e.g.::

    nice -n 10 python benchmarks/bench_ventilator_trade_off.py --seeds 10
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mechopt import minimize  # noqa: E402
from mechopt.optimize.pareto import front_mask, hypervolume, normalisation  # noqa: E402
from mechopt.sim.four_bar.analytic import analytic_batch  # noqa: E402
from mechopt.sim.four_bar.feasibility import check_feasibility  # noqa: E402
from mechopt.studies.catalogue import load_study  # noqa: E402
from mechopt.studies.trade_off_section import with_objectives  # noqa: E402


def brute_force(problem, step: float) -> tuple[np.ndarray, np.ndarray]:  # noqa: ANN001
    """Designs (n, 3) of the grid that satisfy the margins, and their (T_RMS, toggle margin) (n, 2)."""
    axes = [np.arange(lo, hi + 1e-9, step) for lo, hi in problem.bounds]
    X = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    X = X[problem.feasible(X)]
    t_rms, _ = analytic_batch(X, problem.mechanism, check=False)
    toggle = check_feasibility(X, problem.mechanism).toggle_deg + problem.mechanism.toggle_margin_deg
    return X, np.column_stack([t_rms, toggle])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--step", type=float, default=1.0, help="brute-force grid step (mm)")
    ap.add_argument("--budget-front", type=int, default=150)
    ap.add_argument("--budget-limit", type=int, default=60)
    ap.add_argument("--limit", type=float, default=3.0, help="T_RMS limit (N·m)")
    ap.add_argument("--skip-front", action="store_true")
    args = ap.parse_args(argv)
    base = load_study("ventilator", {"engine": "analytic"}).problem
    t0 = time.perf_counter()
    X, Y = brute_force(base, args.step)
    F = np.column_stack([Y[:, 0], -Y[:, 1]])
    ok = np.all(np.isfinite(F), axis=1)
    bf_front = F[ok][front_mask(F[ok])]
    norm = normalisation(bf_front)
    hv_bf = hypervolume(bf_front, norm)
    under = ok & (Y[:, 0] <= args.limit)
    bf_best = float(Y[under, 1].max())
    print(f"brute force: {X.shape[0]} feasible designs on a {args.step:g} mm grid ({time.perf_counter() - t0:.1f} s); "
          f"front of {bf_front.shape[0]}, hypervolume {hv_bf:.5f}; {norm.description}")
    print(f"brute force: largest toggle margin with T_RMS <= {args.limit:g} N·m: {bf_best:.3f} deg at "
          f"{base.describe(X[under][np.argmax(Y[under, 1])])}")
    front_p = with_objectives(base, ("t_rms", "-toggle_margin_deg"))
    limit_p = with_objectives(base, "-toggle_margin_deg", {"t_rms": (None, args.limit)})
    ratios, gaps, broken = [], [], 0
    for seed in range(args.seeds):
        if not args.skip_front:
            r = minimize(front_p, args.budget_front, seed=seed)
            # Re-simulated: the front's designs evaluated again, scored in the brute force's normalisation.
            Fr = np.array([[o["t_rms"], -o["toggle_margin_deg"]] for o in
                           (front_p.evaluate(x) for x in np.atleast_2d(r.x))])
            ratio = hypervolume(Fr[front_mask(Fr)], norm) / hv_bf
            ratios.append(ratio)
            print(f"seed {seed}: front of {Fr.shape[0]} from {r.nfev} simulations, hypervolume {100 * ratio:.2f} % "
                  f"of the brute force's (method {r.method_s:.1f} s)", flush=True)
        r = minimize(limit_p, args.budget_limit, seed=seed)
        again = limit_p.evaluate(r.x)
        meets = again["t_rms"] <= args.limit
        broken += int(not meets)
        gap = bf_best - again["toggle_margin_deg"]
        gaps.append(gap)
        print(f"seed {seed}: largest toggle margin {again['toggle_margin_deg']:.3f} deg (brute force - this = "
              f"{gap:+.3f} deg), T_RMS re-simulated {again['t_rms']:.4f} N·m, meets the limit: {meets}", flush=True)
    if ratios:
        print(f"front: median hypervolume {100 * statistics.median(ratios):.2f} % of the brute force's "
              f"(min {100 * min(ratios):.2f} %, {len(ratios)} seeds, {args.budget_front} simulations)")
    print(f"limit: median gap to the brute force {statistics.median(gaps):+.3f} deg (max {max(gaps):+.3f}), "
          f"{broken} of {len(gaps)} answers break the limit when re-simulated ({args.budget_limit} simulations)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
