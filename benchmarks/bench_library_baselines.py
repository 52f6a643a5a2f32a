"""Library baselines (Optuna, SMT, pymoo, nevergrad) against the in-house ones on the ventilator, small budgets.

Every method gets the ventilator's counted problem (analytic engine, the five feasibility margins as constraints,
failed simulations counted) with the same budget; the design it returns is scored by its true T_RMS (analytic
engine, 4000 intervals) against the brute-force optimum 1.758244 N·m (BENCHMARKS.md, issue 5).

Run: ``python benchmarks/bench_library_baselines.py [--budgets 30,60] [--seeds 5] [--methods a,b]``; prints a
Markdown table (median and worst gap over the seeds, calls, wall time per run).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from mechopt.errors import InfeasibleDesignError
from mechopt.optimize.baselines import CountedProblem
from mechopt.optimize.methods import METHODS
from mechopt.sim.four_bar.analytic import simulate_analytic
from mechopt.sim.four_bar.feasibility import check_feasibility
from mechopt.studies.catalogue import load_study

#: Brute-force optimum of the ventilator (analytic engine, 1 mm grid + SLSQP polish), N·m.
T_TRUE = 1.758244

DEFAULT_METHODS = ["optuna_tpe", "optuna_cmaes", "smt_ego", "pymoo_ga", "pymoo_pso", "pymoo_de", "nevergrad_ngopt",
                   "nevergrad_cma", "bayesian", "genetic", "particle_swarm", "differential_evolution", "slsqp"]


def ventilator_problem(budget: int) -> tuple[CountedProblem, object]:
    """The ventilator's counted problem (analytic engine) and its mechanism."""
    design = load_study("ventilator", {"engine": "analytic"}).problem

    def objective(x: np.ndarray) -> float:
        return design.evaluate(np.asarray(x, dtype=float))[design.objective]

    problem = CountedProblem(objective, design.bounds, budget, design.margins, failure_errors=(InfeasibleDesignError,),
                             vectorized_constraints=True)
    return problem, design.mechanism


def true_t_rms(x: np.ndarray, mechanism: object) -> float:
    """T_RMS of a returned design on the fine analytic grid (NaN when none or infeasible), N·m."""
    if x is None or not np.all(np.isfinite(x)) or not check_feasibility(x, mechanism).feasible[0]:
        return math.nan
    return float(simulate_analytic(np.asarray(x, dtype=float), mechanism, n_intervals=4000).t_rms)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--budgets", default="30,60")
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--methods", default=",".join(DEFAULT_METHODS))
    args = parser.parse_args()
    budgets = [int(b) for b in args.budgets.split(",")]
    methods = args.methods.split(",")
    print(f"ventilator, analytic engine, seeds 0..{args.seeds - 1}, gap = T_RMS / {T_TRUE} - 1", flush=True)
    print("| method | budget | median gap | worst gap | best gap | calls (max) | wall per run (s) |")
    print("|---|---|---|---|---|---|---|", flush=True)
    for name in methods:
        for budget in budgets:
            gaps, calls, walls = [], [], []
            for seed in range(args.seeds):
                problem, mechanism = ventilator_problem(budget)
                t0 = time.perf_counter()
                res = METHODS[name].function(problem, seed)
                walls.append(time.perf_counter() - t0)
                calls.append(int(res.nfev))
                t = true_t_rms(res.x if res.success else None, mechanism)
                gaps.append(100.0 * (t / T_TRUE - 1.0) if math.isfinite(t) else math.inf)
            g = np.array(gaps)
            print(f"| {name} | {budget} | {np.median(g):+.2f} % | {np.max(g):+.2f} % | {np.min(g):+.2f} % | "
                  f"{max(calls)} | {np.median(walls):.2f} |", flush=True)


if __name__ == "__main__":
    main()
