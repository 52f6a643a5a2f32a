"""Benchmark of the simulation engines (issue 2): pymunk and analytic time per design, batch throughput.

Run: ``python -m benchmarks.bench_simulation [--designs 100] [--repeats 5]``.  Prints a Markdown table for
BENCHMARKS.md.
numba functions are compiled (warm-up) before anything is timed.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from mechopt.sim.four_bar.analytic import analytic_batch, simulate_analytic
from mechopt.sim.four_bar.feasibility import feasible_mask
from mechopt.sim.four_bar.pymunk_engine import simulate_pymunk
from mechopt.studies.catalogue import load_study


def main() -> None:
    """Run the benchmark and print the table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--designs", type=int, default=100, help="random feasible designs for the per-design timings")
    parser.add_argument("--batch", type=int, default=200_000, help="designs in the batch throughput test")
    parser.add_argument("--repeats", type=int, default=5, help="repeats of the batch timing (median reported)")
    args = parser.parse_args()

    study = load_study("ventilator")
    mech = study.problem.mechanism
    region = study.problem.bounds
    rng = np.random.default_rng(0)
    cloud = rng.uniform(region[:, 0], region[:, 1], size=(20 * args.designs, 3))
    designs = cloud[feasible_mask(cloud, mech)][: args.designs]

    simulate_analytic(designs[0], mech)  # warm-up: numba compile / cache load
    simulate_pymunk(designs[0], mech)
    analytic_batch(designs[:10], mech)

    pym, errs, steps = [], [], []
    for d in designs:
        t0 = time.perf_counter()
        r = simulate_pymunk(d, mech)
        pym.append(time.perf_counter() - t0)
        ref = simulate_analytic(d, mech, n_intervals=4000)
        errs.append(abs(r.t_rms / ref.t_rms - 1.0))
        steps.append(round(0.4 / r.dt))
    ana = []
    for d in designs:
        t0 = time.perf_counter()
        simulate_analytic(d, mech)
        ana.append(time.perf_counter() - t0)

    batch = rng.uniform(region[:, 0], region[:, 1], size=(args.batch, 3))
    times_nocheck, times_check = [], []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        analytic_batch(batch, mech, check=False)
        times_nocheck.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        analytic_batch(batch, mech, check=True)
        times_check.append(time.perf_counter() - t0)

    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"python {platform.python_version()}; {len(designs)} random feasible designs of the ventilator region")
    print()
    print("| quantity | median | min | max | target |")
    print("|---|---|---|---|---|")
    print(f"| pymunk, ms per design (steps per cycle {int(np.median(steps))} median, Richardson pair) | "
          f"{1e3 * np.median(pym):.1f} | {1e3 * np.min(pym):.1f} | {1e3 * np.max(pym):.1f} | "
          "<= 30 (paper CAD: 85 000) |")
    print(f"| pymunk vs analytic, relative T_RMS error | {np.median(errs):.1e} | {np.min(errs):.1e} | "
          f"{np.max(errs):.1e} | <= 5e-3 |")
    print(f"| analytic, ms per design (one call, 800 intervals) | {1e3 * np.median(ana):.2f} | "
          f"{1e3 * np.min(ana):.2f} | {1e3 * np.max(ana):.2f} | |")
    n = args.batch
    print(f"| analytic batch, designs/s (no feasibility check) | {n / np.median(times_nocheck):,.0f} | "
          f"{n / np.max(times_nocheck):,.0f} | {n / np.min(times_nocheck):,.0f} | >= 50,000 |")
    print(f"| analytic batch, designs/s (with feasibility check) | {n / np.median(times_check):,.0f} | "
          f"{n / np.max(times_check):,.0f} | {n / np.min(times_check):,.0f} | >= 50,000 |")
    rowing = _rowing_times()
    print(f"| rowing (paper 003), ms per design (closed form) | {1e3 * np.median(rowing):.3f} | "
          f"{1e3 * np.min(rowing):.3f} | {1e3 * np.max(rowing):.3f} | <= 0.2 |")


def _rowing_times(repeats: int = 20, calls: int = 200) -> np.ndarray:
    """Seconds per call of the rowing study's evaluator at the paper's optimum (closed form, no time stepping)."""
    problem = load_study("rowing").problem
    x = np.array([3.3, 13.5])
    problem.evaluate(x)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(calls):
            problem.evaluate(x)
        times.append((time.perf_counter() - t0) / calls)
    return np.array(times)


if __name__ == "__main__":
    main()
