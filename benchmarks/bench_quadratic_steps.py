"""The default method with and without its quadratic steps (``optimize/auto/quadratic_steps.py``) on the landscapes
of ``bench_unseen.py``, 10 seeds, side by side: what the steps cost or bring where no method choice looked.

Each seed runs once with the steps, counting those taken.  Where it took none, the run without the steps would
simulate the same designs, so it is not repeated.  Otherwise the same seed runs again with the steps switched off.
The steps are switched off by replacing ``QuadraticSteps.propose`` with a method that never proposes; that is
the "before" of ``docs/guide/valleys-default.md``.  One JSON line per seed is printed, then a Markdown table.  The
table gives the median gap in % of the range, the spread of the 10-seed halves (|median of seeds 0-4 − median of
seeds 5-9|) and the steps taken over the seeds.

Run::

    nice -n 10 python benchmarks/bench_quadratic_steps.py > quadratic_steps.jsonl
    python benchmarks/bench_quadratic_steps.py --functions griewank8 zakharov8 --seeds 10
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import warnings
from pathlib import Path

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_unseen  # noqa: E402

import mechopt.optimize.auto.quadratic_steps as quadratic_steps  # noqa: E402
from mechopt import minimize  # noqa: E402
from mechopt.studies.benchmark_functions import TestFunction  # noqa: E402

_PROPOSE = quadratic_steps.QuadraticSteps.propose


def _run(cls: type[TestFunction], budget: int, seed: int, steps_on: bool) -> tuple[float, int]:
    """Gap in % of the range at the answer of one seeded run, and the quadratic steps it took."""
    taken = [0]

    def counting(self: quadratic_steps.QuadraticSteps, U: np.ndarray, values: np.ndarray, allowed) -> np.ndarray:
        x = _PROPOSE(self, U, values, allowed)
        taken[0] += x.shape[0]
        return x

    def never(self: quadratic_steps.QuadraticSteps, U: np.ndarray, values: np.ndarray, allowed) -> np.ndarray:
        return np.zeros((0, self.dim))

    quadratic_steps.QuadraticSteps.propose = counting if steps_on else never
    try:
        p = cls()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = minimize(p, budget, method="auto", seed=seed)
    finally:
        quadratic_steps.QuadraticSteps.propose = _PROPOSE
    return 100.0 * (float(r.fun) - p.f_min) / p.f_range, taken[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    names = list(bench_unseen.FUNCTIONS)
    ap.add_argument("--functions", nargs="+", default=names, choices=names)
    ap.add_argument("--seeds", type=int, default=10)
    args = ap.parse_args()
    rows = []
    for name in args.functions:
        # Once per function: the class estimates the range from 200,000 random designs.
        cls, budget = bench_unseen.problem_class(name), bench_unseen.FUNCTIONS[name][5]
        for seed in range(args.seeds):
            on, steps = _run(cls, budget, seed, True)
            off = _run(cls, budget, seed, False)[0] if steps else on
            rows.append({"function": name, "budget": budget, "seed": seed,
                         "gap_on": on, "gap_off": off, "steps": steps})
            print(json.dumps(rows[-1]), flush=True)
    print("\n| function | budget | without the steps | halves | with | halves | steps taken |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    h = args.seeds // 2
    for name in args.functions:
        rs = [r for r in rows if r["function"] == name]
        cols = []
        for k in ("gap_off", "gap_on"):
            g = [r[k] for r in rs]
            halves = abs(statistics.median(g[:h]) - statistics.median(g[h:])) if h else float("nan")
            cols += [f"{statistics.median(g):.4g}", f"{halves:.2g}"]
        print(f"| {name} | {rs[0]['budget']} | " + " | ".join(cols) + f" | {sum(r['steps'] for r in rs)} |")


if __name__ == "__main__":
    main()
