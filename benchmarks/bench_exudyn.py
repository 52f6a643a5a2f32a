"""Benchmark of the Exudyn engine (issue 11): accuracy against the analytic engine and time per simulation.

Run: ``python -m benchmarks.bench_exudyn [--random 30] [--boundary 10] [--toggle 10] [--seed 0] [--pool]``.
Prints Markdown tables for BENCHMARKS.md.

Designs (ventilator study, seeded): random feasible ones; feasible ones less than 1 mm from losing assembly
somewhere in the stroke; feasible ones exactly at the toggle margin (toggle margin in [0, 1e-6]°); and, reported
apart, movable designs 0.05–1 mm from the assembly boundary that violate the toggle margin (the sampler visits
them).  The reference is the analytic engine on 4000 intervals.  The three engines are timed design by design in
the same loop (default settings; numba compiled and Exudyn imported before anything is timed); wall and CPU times
are both given because the machine is shared.  ``--pool`` also runs the Exudyn designs through a 2-process pool
and checks that the results are bit-identical to the in-process ones.
"""

from __future__ import annotations

import argparse
import functools
import multiprocessing
import os
import platform
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from scipy.optimize import brentq

from mechopt.sim.four_bar.analytic import simulate_analytic
from mechopt.sim.four_bar.exudyn_engine import simulate_exudyn
from mechopt.sim.four_bar.feasibility import check_feasibility
from mechopt.sim.four_bar.kinematics import crank_angle
from mechopt.sim.four_bar.pymunk_engine import simulate_pymunk
from mechopt.sim.four_bar.simulate import simulate
from mechopt.studies.catalogue import load_study


def _toggle_margin_designs(mech, inside, outside, n):
    """Feasible designs with toggle margin in [0, 1e-6]° on segments from feasible to toggle-violating designs."""
    found = []
    for a, b in zip(inside, outside, strict=False):
        def toggle(s, a=a, b=b):
            return check_feasibility(a + s * (b - a), mech).toggle_deg[0]

        s = brentq(toggle, 0.0, 1.0, xtol=1e-13)
        while toggle(s) < 0:
            s -= 1e-12
        x = a + s * (b - a)
        r = check_feasibility(x, mech)
        if r.feasible[0] and r.toggle_deg[0] <= 1e-6:
            found.append(x)
        if len(found) == n:
            break
    return found


def _movable_boundary_designs(study, mech):
    """Movable designs 0.05–1 mm from the assembly boundary along |AB| from the paper's optima (toggle violated)."""
    out = []
    for name in ("paper_global_optimum", "paper_local_optimum"):
        base = study.design(name)
        for mm in (0.05, 0.2, 1.0):
            ab = brentq(lambda ab, b=base, m=mm: check_feasibility((b[0], ab, b[2]), mech).assembly_stroke_mm[0] - m,
                        base[1], base[1] + 40.0, xtol=1e-10)
            out.append(np.array([base[0], ab, base[2]]))
    return out


def _timed(fn, *args, **kwargs):
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - w0, time.process_time() - c0


def _drift(design, mech, sim) -> float:
    """Largest loop-closure gap (relative to |OA|) and crank-angle drift (rad) of an Exudyn run."""
    oa, ab, bc = design
    xc, yc = mech.pivot_c
    gap = np.hypot(xc + bc * np.cos(sim.psi) - oa * np.cos(sim.theta), yc + bc * np.sin(sim.psi)
                   - oa * np.sin(sim.theta)) - ab
    theta_ref = np.unwrap(crank_angle(design, mech.pivot_c, mech.motion(sim.t)[0], mech.branch)[0])
    return max(np.max(np.abs(gap)) / oa, np.max(np.abs(sim.theta - theta_ref)))


def main() -> None:
    """Run the benchmark and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--random", type=int, default=30, help="random feasible designs")
    parser.add_argument("--boundary", type=int, default=10, help="feasible designs < 1 mm from the assembly boundary")
    parser.add_argument("--toggle", type=int, default=10, help="feasible designs at the toggle margin")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--pool", action="store_true", help="also run the designs in a 2-process pool")
    args = parser.parse_args()

    study = load_study("ventilator")
    mech = study.problem.mechanism
    box = np.array([(v.lower, v.upper) for v in study.problem.variables])
    rng = np.random.default_rng(args.seed)
    cloud = rng.uniform(box[:, 0], box[:, 1], size=(200_000, 3))
    report = check_feasibility(cloud, mech)
    groups = {
        "random feasible": list(cloud[report.feasible][: args.random]),
        "feasible, < 1 mm from assembly boundary": list(
            cloud[report.feasible & (report.assembly_stroke_mm < 1.0)][: args.boundary]),
        "feasible, at the toggle margin": _toggle_margin_designs(
            mech, cloud[report.feasible][args.random:], cloud[report.movable & (report.toggle_deg < 0)], args.toggle),
    }
    feasible_groups = list(groups)
    groups["movable only, 0.05-1 mm from assembly boundary"] = _movable_boundary_designs(study, mech)

    # Warm-up: numba compile or cache load, Exudyn import.
    warm = groups["random feasible"][0]
    simulate_analytic(warm, mech)
    simulate_pymunk(warm, mech)
    simulate_exudyn(warm, mech)

    rows = {}
    times = {"exudyn": [], "pymunk": [], "analytic": []}
    cpu = {"exudyn": [], "pymunk": [], "analytic": []}
    drift = []
    for label, designs in groups.items():
        errs, errs_max = [], []
        for d in designs:
            exu, w, c = _timed(simulate_exudyn, d, mech)
            pym, wp, cp = _timed(simulate_pymunk, d, mech)
            ana, wa, ca = _timed(simulate_analytic, d, mech)
            if label in feasible_groups:
                for name, wall, proc in (("exudyn", w, c), ("pymunk", wp, cp), ("analytic", wa, ca)):
                    times[name].append(wall)
                    cpu[name].append(proc)
            ref = simulate_analytic(d, mech, n_intervals=4000)
            errs.append(abs(exu.t_rms / ref.t_rms - 1.0))
            errs_max.append(abs(exu.t_max / ref.t_max - 1.0))
            drift.append(_drift(d, mech, exu))
            del pym, ana
        rows[label] = (len(designs), errs, errs_max)

    n_feasible = sum(rows[g][0] for g in feasible_groups)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores (shared), "
          f"python {platform.python_version()}; ventilator study, seed {args.seed}; {n_feasible} feasible designs; "
          "reference: analytic engine, 4000 intervals; Exudyn: trapezoidal index-2, 200 steps (2 ms)")
    print()
    print("| designs | n | Exudyn vs analytic T_RMS rel. error, median | max | T_max rel. error, max |")
    print("|---|---|---|---|---|")
    all_errs = []
    for label, (n, errs, errs_max) in rows.items():
        if label in feasible_groups:
            all_errs += errs
        print(f"| {label} | {n} | {np.median(errs):.1e} | {np.max(errs):.1e} | {np.max(errs_max):.1e} |")
    print(f"| all feasible | {n_feasible} | {np.median(all_errs):.1e} | {np.max(all_errs):.1e} | |")
    print()
    print(f"largest loop-closure / crank-angle drift of the Exudyn runs: {max(drift):.1e} (guard: 1e-3)")
    print()
    print(f"| engine (default settings), per simulation, {n_feasible} feasible designs | wall ms, median | "
          "CPU ms, median | wall ms, max |")
    print("|---|---|---|---|")
    notes = {"exudyn": "200 steps", "pymunk": "auto step, Richardson pair", "analytic": "800 intervals"}
    for name in ("exudyn", "pymunk", "analytic"):
        print(f"| {name} ({notes[name]}) | {1e3 * np.median(times[name]):.1f} | {1e3 * np.median(cpu[name]):.1f} | "
              f"{1e3 * np.max(times[name]):.1f} |")

    if args.pool:
        designs = [d for g in feasible_groups for d in groups[g]]
        run = functools.partial(simulate, mechanism=mech, engine="exudyn")
        methods = multiprocessing.get_all_start_methods()
        context = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
        t0 = time.perf_counter()
        with ProcessPoolExecutor(max_workers=2, mp_context=context) as pool:
            remote = list(pool.map(run, designs))
        wall = time.perf_counter() - t0
        same = all(r.t_rms == run(d).t_rms for r, d in zip(remote, designs, strict=True))
        print()
        print(f"2-process pool (forkserver), {len(designs)} Exudyn simulations: {wall:.1f} s wall including worker "
              f"start-up; T_RMS bit-identical to in-process runs: {same}")


if __name__ == "__main__":
    main()
