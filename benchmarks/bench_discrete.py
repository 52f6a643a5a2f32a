"""Discrete variables: the ventilator at drawing resolution against the continuous ventilator, and the default
method's grid-aware proposals against the door alone (proposals snapped by the sampler, the method unaware).

Part ``ventilator``: ``auto`` on the ventilator (analytic engine) with continuous lengths and with the three lengths on
a 0.1 mm grid (study ``ventilator-drawing``), side by side per seed: T_RMS, whether the continuous answer rounded to
0.1 mm is feasible, whether the grid's answer meets every margin, and its cost against the continuous study's optimum
(30.000, 70.563, 254.585) mm.

Part ``auto``: on a mixed problem (continuous, 0.1 grid, integer, catalogue) and on Hartmann-3 on a 0.05 grid (9,261
designs: the acquisition enumerates them), the best value found by ``auto`` as shipped and by ``auto`` with its grid
turned off (the sampler still snaps: the model sees the snapped designs' values at the proposals' places, and repeats
are free but spend proposals).

Run: ``nice -n 10 python benchmarks/bench_discrete.py ventilator --seeds 10 --budget 100`` (``--grid-only``: the
grid's runs alone) and
``nice -n 10 python benchmarks/bench_discrete.py auto --seeds 10 --budget 30``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
import warnings
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

import mechopt  # noqa: E402
from mechopt import DesignProblem, Variable  # noqa: E402
from mechopt.optimize.auto import design_grid  # noqa: E402
from mechopt.studies.benchmark_functions import Hartmann3  # noqa: E402
from mechopt.studies.catalogue import load_study  # noqa: E402

CONTINUOUS_OPTIMUM = np.array([30.0, 70.563, 254.585])


class MixedBowl(DesignProblem):
    """One variable of each kind; the best allowed design by brute force is printed by :func:`mixed_best`."""

    name = "mixed_bowl"
    variables = (Variable("x", 0.0, 1.0), Variable("s", 0.0, 2.0, step=0.1), Variable("n", 1, 8, integer=True),
                 Variable("d", values=(0.5, 0.63, 0.8, 1.0)))
    constraints = ("room",)
    outputs = ("f",)
    objective = "f"

    def margins(self, X):
        return (2.2 - X[:, 0] - X[:, 1])[:, None]

    def evaluate(self, x):
        f = (x[0] - 0.31) ** 2 + (x[1] - 1.27) ** 2 + 0.1 * (x[2] - 4.4) ** 2 + (x[3] - 0.7) ** 2 + 0.2 * x[0] * x[3]
        return {"f": float(f)}


def mixed_best() -> float:
    """Brute force: the continuous x on a 1e-4 grid, every allowed value of the others."""
    p = MixedBowl()
    axes = [np.linspace(0, 1, 10001), *(v.allowed() for v in p.variables[1:])]
    X = np.array(np.meshgrid(*axes, indexing="ij")).reshape(4, -1).T
    X = X[p.feasible(X)]
    f = (X[:, 0] - 0.31) ** 2 + (X[:, 1] - 1.27) ** 2 + 0.1 * (X[:, 2] - 4.4) ** 2 + (X[:, 3] - 0.7) ** 2 \
        + 0.2 * X[:, 0] * X[:, 3]
    return float(f.min())


class GridHartmann3(Hartmann3):
    """Hartmann-3 with each variable on a 0.05 grid: 21³ = 9,261 designs."""

    name = "hartmann3_grid"
    variables = tuple(Variable(f"x{i + 1}", 0.0, 1.0, step=0.05) for i in range(3))


def grid_hartmann_best() -> float:
    p = GridHartmann3()
    X = np.array(np.meshgrid(*(v.allowed() for v in p.variables), indexing="ij")).reshape(3, -1).T
    return float(min(p.evaluate(x)["f"] for x in X))


def ventilator(seeds: int, budget: int, grid_only: bool = False) -> None:
    base = load_study("ventilator", {"engine": "analytic"}).problem
    grid = load_study("ventilator-drawing", {"engine": "analytic"}).problem
    ref = base.evaluate(CONTINUOUS_OPTIMUM)["t_rms"]
    print(f"continuous optimum {CONTINUOUS_OPTIMUM.tolist()} mm: T_RMS {ref:.6f} N·m (analytic)")
    print("| seed | continuous T_RMS | its rounding feasible | 0.1 mm grid answer (mm) | T_RMS | min margin | "
          "cost vs continuous optimum | s |")
    print("|---|---|---|---|---|---|---|---|")
    costs = []
    for seed in range(seeds):
        t0 = time.perf_counter()
        rc = None if grid_only else mechopt.minimize(base, budget=budget, seed=seed)
        rg = mechopt.minimize(grid, budget=budget, seed=seed)
        rounded_ok = "—" if rc is None else ("yes" if grid.feasible(grid.snap(rc.x))[0] else "no")
        margin = float(grid.constraint_margins(np.asarray(rg.x)[None, :]).min())
        cost = 100 * (rg.fun / ref - 1)
        costs.append(cost)
        print(f"| {seed} | {'—' if rc is None else f'{rc.fun:.5f}'} | {rounded_ok} | {np.round(rg.x, 1).tolist()} | "
              f"{rg.fun:.5f} | {margin:.4f} | {cost:+.3f} % | {time.perf_counter() - t0:.0f} |", flush=True)
    print(f"median cost {statistics.median(costs):+.3f} %, worst {max(costs):+.3f} %, within 0.5 %: "
          f"{sum(c <= 0.5 for c in costs)} of {len(costs)}")


def auto(seeds: int, budget: int) -> None:
    cases = [(MixedBowl(), mixed_best()), (GridHartmann3(), grid_hartmann_best())]
    of = design_grid.DesignGrid.of
    print("| problem | seed | auto (grid-aware) | auto, door only | best allowed |")
    print("|---|---|---|---|---|")
    for problem, best in cases:
        gaps = {"aware": [], "door": []}
        for seed in range(seeds):
            aware = mechopt.minimize(problem, budget=budget, seed=seed).fun
            design_grid.DesignGrid.of = classmethod(lambda cls, p: None)
            try:
                door = mechopt.minimize(problem, budget=budget, seed=seed).fun
            finally:
                design_grid.DesignGrid.of = of
            gaps["aware"].append(aware - best)
            gaps["door"].append(door - best)
            print(f"| {problem.name} | {seed} | {aware:.6g} | {door:.6g} | {best:.6g} |", flush=True)
        print(f"| {problem.name} | median gap | {statistics.median(gaps['aware']):.4g} | "
              f"{statistics.median(gaps['door']):.4g} | |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("part", choices=("ventilator", "auto"))
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--budget", type=int, default=100)
    parser.add_argument("--grid-only", action="store_true", help="ventilator: only the 0.1 mm grid's runs")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    print(f"$ python benchmarks/bench_discrete.py {' '.join(sys.argv[1:])}")
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    if args.part == "ventilator":
        ventilator(args.seeds, args.budget, args.grid_only)
    else:
        auto(args.seeds, args.budget)


if __name__ == "__main__":
    main()
