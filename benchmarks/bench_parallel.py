"""Parallel simulations (issue 28): wall time, rounds, idle share and answer against the number of workers.

An external-command study whose command sleeps ``--sleep`` seconds (default 1) per design, then prints a suite
function's value (pure Python, no import of numpy: a process start costs ~20 ms of CPU, so 16 at once fit on 2
cores); each run goes through :func:`mechopt.minimize` with ``workers`` local processes (or a Dask ``LocalCluster``,
``--dask``), the executor's start included in the wall time.

Two parts:

* ``timed``: one seed per row (the slow part: a run at budget 300 on one worker takes five minutes), every method,
  workers and budget asked for; columns: wall time, rounds (calls that dispatched designs), idle share of the
  workers, seconds waiting for simulations, seconds of the method's own computing, answer and its gap in % of the
  function's range.
* ``answers``: the same methods without sleeping, in-process, with the batch size of ``workers`` forced (the
  proposals depend on the batch size and the simulated values only, never on timing), over ``--seeds`` seeds: the
  median gap at each batch size against that of one worker.

Run: ``python benchmarks/bench_parallel.py`` (everything, about 45 min on 2 cores) or, e.g.,
``python benchmarks/bench_parallel.py --part timed --methods sparse --functions hartmann3 --workers 1 8
--budgets 60``.
"""

from __future__ import annotations

import argparse
import contextlib
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mechopt import minimize  # noqa: E402
from mechopt.optimize.methods import METHODS  # noqa: E402
from mechopt.optimize.minimize import _options, run_method  # noqa: E402
from mechopt.optimize.sparse.sampler import Sampler  # noqa: E402
from mechopt.runs.executors import InProcessExecutor  # noqa: E402
from mechopt.runs.store import SampleStore  # noqa: E402
from mechopt.studies.benchmark_functions import SUITE  # noqa: E402
from mechopt.studies.catalogue import load_study  # noqa: E402

#: The simulator: a suite function in pure Python after a sleep, design JSON on stdin, outputs JSON on stdout.
SIM = '''import json, math, sys, time
H3A = [[3.0, 10, 30], [0.1, 10, 35], [3.0, 10, 30], [0.1, 10, 35]]
H3P = [[0.3689, 0.1170, 0.2673], [0.4699, 0.4387, 0.7470], [0.1091, 0.8732, 0.5547], [0.0381, 0.5743, 0.8828]]
H6A = [[10, 3, 17, 3.5, 1.7, 8], [0.05, 10, 17, 0.1, 8, 14], [3, 3.5, 1.7, 10, 17, 8], [17, 8, 0.05, 10, 0.1, 14]]
H6P = [[0.1312, 0.1696, 0.5569, 0.0124, 0.8283, 0.5886], [0.2329, 0.4135, 0.8307, 0.3736, 0.1004, 0.9991],
       [0.2348, 0.1451, 0.3522, 0.2883, 0.3047, 0.6650], [0.4047, 0.8828, 0.8732, 0.5743, 0.1091, 0.0381]]
C = [1.0, 1.2, 3.0, 3.2]
def hartmann(x, A, P):
    return -sum(c * math.exp(-sum(a * (xi - p) ** 2 for a, xi, p in zip(Ai, x, Pi))) for c, Ai, Pi in zip(C, A, P))
def cosine_bowl(x):
    return sum((xi - 0.3) ** 2 for xi in x) - 0.3 * math.prod(math.cos(3 * math.pi * (xi - 0.3)) for xi in x)
FUNCTIONS = {"hartmann3": lambda x: hartmann(x, H3A, H3P), "hartmann6": lambda x: hartmann(x, H6A, H6P),
             "cosine_bowl3": cosine_bowl, "cosine_bowl4": cosine_bowl}
name, sleep = sys.argv[1], float(sys.argv[2])
design = json.load(sys.stdin)
time.sleep(sleep)
x = [design[f"x{i + 1}"] for i in range(len([k for k in design if k.startswith("x")]))]
print(json.dumps({"f": FUNCTIONS[name](x)}))
'''


def study_file(folder: Path, name: str, sleep: float) -> Path:
    """An external-command study of suite function ``name`` whose command sleeps ``sleep`` s a design."""
    (folder / "sim.py").write_text(SIM)
    dim = SUITE[name]().dim
    variables = "\n".join(f"x{i + 1} = [0.0, 1.0]" for i in range(dim))
    path = folder / f"{name}.toml"
    path.write_text(f'name = "{name}-sleep"\nkind = "external"\n[variables]\n{variables}\n[simulator]\n'
                    f'command = ["{{python}}", "-S", "sim.py", "{name}", "{sleep:g}"]\noutputs = ["f"]\n'
                    f'seconds_per_run = {max(sleep, 0.001):g}\n')
    return path


def check_simulator(folder: Path, names: list[str]) -> None:
    """The command's values equal the suite's (a wrong formula would make every gap meaningless)."""
    rng = np.random.default_rng(0)
    for name in names:
        problem = load_study(study_file(folder, name, 0.0)).problem
        for x in rng.random((3, problem.dim)):
            expected = float(SUITE[name]()(x[None, :])[0])
            got = problem.evaluate(x)["f"]
            assert abs(got - expected) <= 1e-9 * max(1.0, abs(expected)), (name, got, expected)


def timed(folder: Path, name: str, method: str, budget: int, workers: int, seed: int, sleep: float,
          scheduler=None) -> dict:
    """One run on the sleeping command: wall time (executor start included), rounds, idle share, answer."""
    problem = load_study(study_file(folder, name, sleep)).problem
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = minimize(problem, budget=budget, method=method, seed=seed, workers=workers, scheduler=scheduler)
    wall = time.perf_counter() - t0
    s = res.sampling
    return {"function": name, "method": method, "budget": budget, "workers": workers, "seed": seed, "wall_s": wall,
            "rounds": s["rounds"], "idle": s["idle_share"], "waiting_s": s["waiting_s"], "method_s": s["method_s"],
            "nfev": res.nfev, "fun": float(res.fun), "gap": SUITE[name]().gap(res.fun)}


class _Batch(InProcessExecutor):
    """In-process, one design after the other, but announcing ``workers`` so the method proposes that many."""

    def __init__(self, workers: int) -> None:
        super().__init__()
        self.workers = workers
        self.description = f"in-process, batches of {workers}"


def answer(name: str, method: str, budget: int, batch: int, seed: int) -> float:
    """The gap (share of the range) of one run without sleeping, at batch size ``batch``."""
    problem = SUITE[name]()
    with tempfile.TemporaryDirectory() as tmp, SampleStore(Path(tmp) / "s.sqlite") as store, \
            warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sampler = Sampler(problem, store, _Batch(batch), progress=False)
        res = run_method(problem, method, _options(problem, None, budget, seed), sampler, lambda _line: None)
    return problem.gap(res.fun)


def print_timed(rows: list[dict], header: bool = False) -> None:
    if header:
        print("| function | method | budget | workers | seed | wall (s) | rounds | idle | waiting (s) | method (s) | "
              "sims | answer | gap % of range |")
        print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['function']} | {r['method']} | {r['budget']} | {r['workers']} | {r['seed']} | {r['wall_s']:.1f} | "
              f"{r['rounds']} | {r['idle']:.0%} | {r['waiting_s']:.1f} | {r['method_s']:.1f} | {r['nfev']} | "
              f"{r['fun']:.5g} | {100 * r['gap']:.2f} |", flush=True)


def run_timed(args: argparse.Namespace, folder: Path) -> list[dict]:
    rows = []
    for name in args.functions:
        dim = SUITE[name]().dim
        for method in args.methods:
            if not METHODS[method].takes_dim(dim):
                continue  # the line methods take 2 to 4 variables
            for budget in args.budgets:
                for workers in args.workers:
                    if workers == 1 and budget > 60 and not args.slow:
                        continue  # five minutes a row: --slow runs it
                    rows.append(timed(folder, name, method, budget, workers, args.seed, args.sleep))
                    print_timed(rows[-1:], header=len(rows) == 1)
    return rows


def run_dask(args: argparse.Namespace, folder: Path) -> list[dict]:
    from distributed import LocalCluster

    rows = []
    with LocalCluster(n_workers=2, threads_per_worker=4, processes=True, dashboard_address=None) as cluster:
        for method in args.methods:
            row = timed(folder, args.functions[0], method, 60, 8, args.seed, args.sleep, scheduler=cluster)
            row["workers"] = "Dask 2×4"
            rows.append(row)
            print_timed(rows[-1:], header=args.part == "dask" and len(rows) == 1)
    return rows


def run_answers(args: argparse.Namespace) -> None:
    print(f"| function | method | budget | batch | median gap % of range ({args.seeds} seeds) | worst | "
          "|median − median at batch 1| % |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for name in args.functions:
        for method in args.methods:
            if not METHODS[method].takes_dim(SUITE[name]().dim):
                continue
            for budget in args.answer_budgets:
                base = None
                for batch in args.workers:
                    gaps = [answer(name, method, budget, batch, seed) for seed in range(args.seeds)]
                    med = statistics.median(gaps)
                    base = med if base is None else base
                    print(f"| {name} | {method} | {budget} | {batch} | {100 * med:.3f} | {100 * max(gaps):.3f} | "
                          f"{100 * abs(med - base):.3f} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--part", choices=("timed", "answers", "dask", "all"), default="all")
    parser.add_argument("--functions", nargs="+", default=["hartmann3", "cosine_bowl3", "hartmann6"])
    parser.add_argument("--methods", nargs="+", default=["sparse", "sparse-global", "auto"])
    parser.add_argument("--workers", nargs="+", type=int, default=[1, 4, 8, 16])
    parser.add_argument("--budgets", nargs="+", type=int, default=[60, 300])
    parser.add_argument("--answer-budgets", nargs="+", type=int, default=[60])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0, help="the seed of the timed rows")
    parser.add_argument("--sleep", type=float, default=1.0)
    parser.add_argument("--slow", action="store_true", help="also time one worker at budgets above 60")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp, contextlib.ExitStack():
        folder = Path(tmp)
        check_simulator(folder, args.functions)
        print(f"command sleeping {args.sleep:g} s a design; 2 cores; timed rows: seed {args.seed} only")
        if args.part in ("timed", "all"):
            run_timed(args, folder)
        if args.part in ("dask", "all"):
            run_dask(args, folder)
        if args.part in ("answers", "all"):
            run_answers(args)


if __name__ == "__main__":
    main()
