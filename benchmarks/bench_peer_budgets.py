"""Does every library peer spend the whole budget it is given?  Simulations spent per peer at fixed (d, budget).

Each peer (Optuna TPE and CMA-ES, pymoo GA, PSO and DE, nevergrad NGOpt and CMA, SMT EGO) runs through
:func:`mechopt.minimize` exactly as ``mechopt compare`` runs it, seed 0, on a test function of the suite at the
points (d, budget) = (3, 30), (3, 300), (6, 300), (8, 500), (12, 1000): Hartmann-3, Hartmann-6, Levy-8 and, since
the suite has no 12-D function, Levy in 12-D defined here (Laguna & Martí 2005; global 0 at (1, ..., 1) on
[-10, 10]^12).  A suite function that the installed mechopt does not have is replaced by Levy of the same dimension.
SMT EGO runs only within its limit in ``mechopt compare`` (:func:`mechopt.optimize.baselines.smt_ego.max_budget`):
at (3, 30) and at (3, limit) and (8, limit), where the time of its last steps is what the limit rests on (a step's
cost grows with the cube of the samples and with the dimension).

Printed: a Markdown table, one row per peer and point: simulations spent / budget, wall and CPU time of the run
(CPU: this process's, which BLAS threads limited to one makes the time of the run on an idle core), and the
method's message when it stopped short.  Then EGO's per-step times.

Run: ``python -m benchmarks.bench_peer_budgets [--peers a,b] [--no-ego-limit]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

import mechopt
from mechopt.optimize.baselines.smt_ego import max_budget as ego_max_budget
from mechopt.optimize.methods import METHODS
from mechopt.optimize.problem import Variable
from mechopt.studies.benchmark_functions import SUITE, TestFunction

#: The points of the issue: (dimension, budget, suite function).
POINTS = [(3, 30, "hartmann3"), (3, 300, "hartmann3"), (6, 300, "hartmann6"), (8, 500, "levy8"),
          (12, 1000, "levy12")]


def levy(X: np.ndarray) -> np.ndarray:
    """Levy's function at designs X (n, d), shape (n,); global minimum 0 at (1, ..., 1)."""
    w = 1.0 + (np.atleast_2d(X) - 1.0) / 4.0
    head = np.sin(np.pi * w[:, 0]) ** 2
    body = np.sum((w[:, :-1] - 1.0) ** 2 * (1.0 + 10.0 * np.sin(np.pi * w[:, :-1] + 1.0) ** 2), axis=1)
    tail = (w[:, -1] - 1.0) ** 2 * (1.0 + np.sin(2.0 * np.pi * w[:, -1]) ** 2)
    return head + body + tail


def levy_problem(d: int) -> TestFunction:
    """Levy on [-10, 10]^d as a test function of the suite's kind."""

    class Levy(TestFunction):
        name = f"levy{d}"
        variables = tuple(Variable(f"x{i + 1}", -10.0, 10.0) for i in range(d))
        f_min = 0.0
        x_min = np.ones((1, d))

        def function(self, X: np.ndarray) -> np.ndarray:
            return levy(X)

    return Levy()


def problem_for(d: int, name: str) -> TestFunction:
    """The suite's function ``name`` when it has it (and it is d-dimensional), else Levy in d dimensions."""
    cls = SUITE.get(name)
    if cls is not None and len(cls.variables) == d:
        return cls()
    return levy_problem(d)


@dataclass
class Timed:
    """An evaluator that time-stamps its calls: the gaps between them are the method's steps."""

    evaluate_design: Callable[[np.ndarray], dict[str, float]]
    stamps: list[tuple[float, float]]

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        self.stamps.append((time.perf_counter(), time.process_time()))
        return self.evaluate_design(x)


def timed(problem: TestFunction) -> tuple[TestFunction, list[tuple[float, float]]]:
    """The problem with its ``evaluate`` recording (wall, CPU) time stamps, in s."""
    stamps: list[tuple[float, float]] = []
    recorder = Timed(problem.evaluate, stamps)  # the class's evaluate, bound before it is shadowed
    problem.evaluate = recorder.evaluate  # type: ignore[method-assign]  # an instance attribute: this run only
    return problem, stamps


def run(peer: str, d: int, budget: int, name: str) -> tuple[dict, list[tuple[float, float]]]:
    """One seeded run of ``peer`` through :func:`mechopt.minimize`; its row and its evaluation time stamps."""
    problem, stamps = timed(problem_for(d, name))
    wall, cpu = time.perf_counter(), time.process_time()
    try:
        res = mechopt.minimize(problem, budget=budget, method=peer, seed=0)
        nfev, message = int(res.nfev), " ".join(str(res.message).split())
        if res.nfailed:  # a benchmark of the budget, not of failures: say it when simulations failed
            message = f"{res.nfailed} failed simulations; {message}"
    except Exception as exc:  # a peer's error is what this benchmark looks for: report it, go on
        nfev, message = len(stamps), f"raised {type(exc).__name__}: {exc}"
    row = {"peer": peer, "d": d, "budget": budget, "function": problem.name, "nfev": nfev,
           "wall_s": time.perf_counter() - wall, "cpu_s": time.process_time() - cpu, "message": message}
    return row, stamps


def main() -> int:
    """Run every peer at every point; print the table and EGO's step times; exit 1 if a run stopped short."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    library = [name for name, m in METHODS.items() if m.spends_whole_budget]
    parser.add_argument("--peers", default=",".join(library), help="comma-separated library peers")
    parser.add_argument("--no-ego-limit", action="store_true", help="skip EGO's runs at its limit (the slow ones)")
    args = parser.parse_args()
    peers = [p for p in args.peers.split(",") if p]
    unknown = [p for p in peers if p not in METHODS or METHODS[p].own]
    if unknown:
        parser.error(f"unknown peer {unknown[0]!r}; expected some of {', '.join(library)}")
    print("| peer | d | budget | function | simulations spent | wall (s) | CPU (s) | note |")
    print("|---|---|---|---|---|---|---|---|")
    short, ego_steps = 0, {}
    for peer in peers:
        points = POINTS
        capped = METHODS[peer].max_budget is not None  # SMT's EGO: its steps refit Kriging on every sample
        if capped:
            points = [p for p in POINTS if p[1] <= ego_max_budget(p[0])]
            if not args.no_ego_limit:
                points += [(3, ego_max_budget(3), "hartmann3"), (8, ego_max_budget(8), "levy8")]
        for d, budget, name in points:
            row, stamps = run(peer, d, budget, name)
            spent = row["nfev"] == budget
            short += not spent
            note = "" if spent else f"STOPPED SHORT: {row['message']}"
            if spent and "failed simulations" in row["message"]:
                note = row["message"]
            print(f"| {peer} | {d} | {budget} | {row['function']} | {row['nfev']} / {budget} | {row['wall_s']:.1f} | "
                  f"{row['cpu_s']:.1f} | {note} |", flush=True)
            if capped and len(stamps) > 6:
                wall = np.diff([s[0] for s in stamps])
                cpu = np.diff([s[1] for s in stamps])
                ego_steps[(d, budget)] = (float(np.mean(wall[-5:])), float(np.mean(cpu[-5:])))
    if ego_steps:
        print("\nSMT EGO, mean time of its last 5 steps (one Kriging refit + infill search each):")
        for (d, budget), (wall, cpu) in ego_steps.items():
            print(f"- d = {d}, budget {budget}: {wall:.2f} s wall, {cpu:.2f} s CPU per step")
    print(f"\n{short} run(s) stopped before their budget" if short else "\nevery run spent its whole budget")
    return 1 if short else 0


if __name__ == "__main__":
    sys.exit(main())
