"""The default method on landscapes outside the suite: functions no part of mechopt was measured or tuned on.

Issue 22 judges the default "on landscapes you have not seen".  These are defined here and nowhere in the package, so
that no method choice can lean on them: Michalewicz (steep narrow valleys on a flat plateau), Schwefel (the best
basin far from the second), Rastrigin, Griewank (a bowl under fine ripples), a staircase (a simulator whose output
moves in steps: a mesh, a tolerance), Zakharov (smooth, ill-conditioned), a minimum at a corner of the box, Ackley,
Levy and Rosenbrock in 10-12 variables, and two functions of 2 and 3 variables hidden among 12 and 10 (most
variables irrelevant).  Each method runs through :func:`mechopt.minimize` at the budget of the table below; the gap is
(f(x) − f_min) / range, the range estimated as the largest of 200 000 uniform random designs minus f_min.

Run: ``python benchmarks/bench_unseen.py`` (all functions, ``auto`` and the four library peers, 5 seeds; about 20
min on 2 cores) or, e.g., ``python benchmarks/bench_unseen.py --functions michalewicz5 --methods auto smt_ego``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mechopt import minimize  # noqa: E402
from mechopt.studies.benchmark_functions import SUITE, TestFunction, Variable  # noqa: E402


def michalewicz(X: np.ndarray) -> np.ndarray:
    i = np.arange(1, X.shape[1] + 1)
    return -np.sum(np.sin(X) * np.sin(i * X * X / np.pi) ** 20, axis=1)


def schwefel(X: np.ndarray) -> np.ndarray:
    return 418.9829 * X.shape[1] - np.sum(X * np.sin(np.sqrt(np.abs(X))), axis=1)


def rastrigin(X: np.ndarray) -> np.ndarray:
    return 10.0 * X.shape[1] + np.sum(X * X - 10.0 * np.cos(2.0 * np.pi * X), axis=1)


def griewank(X: np.ndarray) -> np.ndarray:
    i = np.arange(1, X.shape[1] + 1)
    return 1.0 + np.sum(X * X, axis=1) / 4000.0 - np.prod(np.cos(X / np.sqrt(i)), axis=1)


def staircase(X: np.ndarray) -> np.ndarray:
    return np.sum(np.floor(10.0 * np.abs(X - 0.37)) / 10.0, axis=1) + 0.05 * np.sum((X - 0.37) ** 2, axis=1)


def zakharov(X: np.ndarray) -> np.ndarray:
    s = np.sum(0.5 * np.arange(1, X.shape[1] + 1) * X, axis=1)
    return np.sum(X * X, axis=1) + s**2 + s**4


def corner(X: np.ndarray) -> np.ndarray:
    return np.sum(X * X + 0.3 * np.sin(5.0 * X), axis=1)


def any_dim(name: str) -> Callable[[np.ndarray], np.ndarray]:
    """A suite function's closed form, which takes any number of columns, for more variables than the suite's."""
    return SUITE[name]().function


def hidden(base: str, active: list[int]) -> Callable[[np.ndarray], np.ndarray]:
    """A suite function of len(active) variables, read from those columns of the unit cube; the rest irrelevant."""
    problem = SUITE[base]()
    lo, hi = problem.bounds[:, 0], problem.bounds[:, 1]
    return lambda X: problem.function(lo + X[:, active] * (hi - lo))


def _corner_min(d: int) -> float:
    """The corner function is a sum of one term a variable: its minimum on [1, 2] from a dense grid."""
    t = np.linspace(1.0, 2.0, 2_000_001)
    return d * float(np.min(t * t + 0.3 * np.sin(5.0 * t)))


#: name: (variables, lower, upper, function, f_min, budget)
FUNCTIONS: dict[str, tuple] = {
    "michalewicz5": (5, 0.0, math.pi, michalewicz, -4.687658, 40),
    "schwefel4": (4, -500.0, 500.0, schwefel, 0.0, 40),
    "staircase4": (4, 0.0, 1.0, staircase, 0.0, 40),
    "corner5": (5, 1.0, 2.0, corner, _corner_min(5), 60),
    "rastrigin6": (6, -5.12, 5.12, rastrigin, 0.0, 150),
    "griewank8": (8, -600.0, 600.0, griewank, 0.0, 200),
    "zakharov8": (8, -5.0, 10.0, zakharov, 0.0, 200),
    "rosenbrock10": (10, -5.0, 10.0, any_dim("rosenbrock6"), 0.0, 150),
    "hartmann3_in10": (10, 0.0, 1.0, hidden("hartmann3", [1, 4, 7]), -3.86278214782076, 150),
    "branin_in12": (12, 0.0, 1.0, hidden("branin", [3, 8]), 0.39788735772973816, 100),
    "ackley12": (12, -10.0, 30.0, any_dim("ackley8"), 0.0, 150),
    "levy12": (12, -10.0, 10.0, any_dim("levy8"), 0.0, 150),
}


def problem_class(name: str) -> type[TestFunction]:
    """A :class:`TestFunction` of the named function, its range estimated from 200 000 random designs."""
    d, lo, hi, f, f_min, _ = FUNCTIONS[name]
    X = np.random.default_rng(0).uniform(lo, hi, (200_000, d))
    return type(name, (TestFunction,), {
        "name": name, "__doc__": f"{name}: outside the suite (benchmarks/bench_unseen.py)",
        "variables": tuple(Variable(f"x{i + 1}", lo, hi) for i in range(d)),
        "f_min": f_min, "f_range": float(np.max(f(X))) - f_min,
        "function": lambda self, X: f(np.atleast_2d(X)),
    })


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--functions", nargs="+", default=list(FUNCTIONS), choices=list(FUNCTIONS))
    parser.add_argument("--methods", nargs="+",
                        default=["auto", "nevergrad_ngopt", "optuna_tpe", "optuna_cmaes", "pymoo_de"])
    parser.add_argument("--seeds", type=int, default=5)
    args = parser.parse_args()
    print("| function | d | budget | method | median gap % of range | best | worst | s a run |")
    print("|---|---:|---:|---|---:|---:|---:|---:|")
    for name in args.functions:
        cls, budget = problem_class(name), FUNCTIONS[name][5]
        for method in args.methods:
            gaps, t0 = [], time.perf_counter()
            for seed in range(args.seeds):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    res = minimize(cls(), budget, method=method, seed=seed)
                gaps.append(100.0 * cls().gap(float(cls().function(res.x)[0])))
            print(f"| {name} | {cls().dim} | {budget} | {method} | {statistics.median(gaps):.4g} | {min(gaps):.4g} | "
                  f"{max(gaps):.4g} | {(time.perf_counter() - t0) / args.seeds:.1f} |", flush=True)


if __name__ == "__main__":
    main()
