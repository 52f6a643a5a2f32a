"""The ventilator under ±0.1 mm uniform tolerances on its three lengths (analytic engine): the nominal optimum's
probability of violating the toggle margin, the robust optimum's checked by 10^4 Monte Carlo designs on the
simulator, its T_RMS cost, the simulations it added; Sobol indices of T_RMS against brute force on the simulator.

Run: ``python benchmarks/bench_tolerance.py [--budget 60] [--seed 0]`` (a few minutes on 2 cores).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

import mechopt
from mechopt.optimize.analysis import sobol

#: A box of the ventilator's feasible region (every design of 10^5 feasible but 0.03 %), for the Sobol check.
REGION = np.array([[33.0, 47.0], [72.0, 79.0], [262.0, 286.0]])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--budget", type=int, default=60)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    problem = mechopt.load_study("ventilator", {"engine": "analytic"}).problem
    tol = mechopt.Tolerances(dict.fromkeys(problem.names, 0.1), distribution="uniform")
    with tempfile.TemporaryDirectory() as tmp:
        store = Path(tmp) / "samples.sqlite"
        t0 = time.perf_counter()
        res = mechopt.minimize(problem, budget=args.budget, method="auto", seed=args.seed, store=store,
                               tolerances=tol, max_violation=0.01, log=print)
        wall = time.perf_counter() - t0
        rng = np.random.default_rng(12345)
        D = rng.uniform(-0.1, 0.1, (10_000, 3))
        for name, x in (("nominal", res.nominal_x), ("robust", res.x)):
            X = x + D
            p = float((problem.constraint_margins(X) < 0).any(axis=1).mean())
            t = problem.evaluate_batch(X)
            print(f"{name}: {problem.describe(x)}  T_RMS {problem.evaluate(x)['t_rms']:.5f} N·m; "
                  f"10^4 MC on the simulator: P(violation) {p:.4f}, mean T_RMS {np.nanmean(t):.5f}")
        print(f"price {100 * res.robust.price:.2f} %; simulations beyond the nominal run {res.robust.simulations}; "
              f"nominal run {res.nfev}; wall {wall:.0f} s")
        brute = sobol(problem.evaluate_batch, REGION, n=2**13, seed=1)
        sens = mechopt.sensitivity(problem, store=store, region=REGION, simulations=30)
        print("\n".join(sens.lines()))
        print(f"brute force first {np.round(brute[0], 3)}, total {np.round(brute[1], 3)}; largest difference "
              f"{max(np.abs(sens.first_order - brute[0]).max(), np.abs(sens.total_order - brute[1]).max()):.4f}")
        if args.out:
            from mechopt.report.tolerance_figures import plot_sobol, plot_tolerance

            out = Path(args.out)
            for name, x in (("nominal", res.nominal_x), ("robust", res.x)):
                a = mechopt.tolerance(problem, x, tol, store=store, simulations=10)
                print("\n".join(a.lines(problem)))
                plot_tolerance(problem, a, out / f"tolerance_{name}.png")
            plot_sobol(sens, out / "sobol.png", "T_RMS")


if __name__ == "__main__":
    main()
