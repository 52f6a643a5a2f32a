"""The default method against the strongest peers on the valleys (studies/valley_functions.py): median f − f* over
seeds, side by side in one run, each run through :func:`mechopt.minimize` (what a user gets).

Every (method, function, budget, seed) is cached in a JSON file (``--cache``) as soon as it ends, so a grid can be
run in parts and resumed; ``--table`` prints the table from the cache alone.  Budgets are written ``10d`` (10 × the
function's dimension) or as a number.  ``--suite-bar`` runs the issue's second bar instead: ``auto`` against
Optuna's GPSampler and BoTorch at 30 simulations on the 3-D and 4-D functions of the existing suite.

Run, e.g.::

    nice -n 10 python benchmarks/bench_valleys.py --dims 3 6 --methods auto py_bobyqa --seeds 10
    nice -n 10 python benchmarks/bench_valleys.py --suite-bar --cache bench_suite_bar.json
    python benchmarks/bench_valleys.py --table
    nice -n 10 python benchmarks/bench_valleys.py --aligned --methods auto --dims 3 6 --cache aligned.json

``--aligned`` runs the same valleys with R = Q = I, their axes along the variables: how far a perfectly learned
rotation of the inputs could take a method.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import shlex
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mechopt import minimize  # noqa: E402
from mechopt.studies.benchmark_functions import SUITE, TestFunction  # noqa: E402
from mechopt.studies.valley_functions import VALLEYS, Valley  # noqa: E402

#: The peers of issue 53: NGOpt, CMA-ES (nevergrad's pycma and Optuna's), COBYQA, Py-BOBYQA, GPSampler, BoTorch.
PEERS = ("nevergrad_ngopt", "nevergrad_cma", "optuna_cmaes", "cobyqa", "py_bobyqa", "optuna_gp", "botorch_qlognei")
KINDS = sorted({name.removeprefix("valley_").rstrip("0123456789") for name in VALLEYS})
#: COBYQA as scipy runs it: one start given the whole budget (the table's ``cobyqa`` splits it over 3 starts by
#: default; leftovers of a converged start go to fresh starts either way).
OPTIONS = {"cobyqa": {"n_starts": 1}}
#: Suffix of a valley's name in the cache and the table when it runs axis-aligned (``--aligned``).
ALIGNED = "_aligned"
SUITE_BAR = sorted(n for n, c in SUITE.items() if not issubclass(c, Valley) and c().dim in (3, 4))


def budget_of(text: str, dim: int) -> int:
    """``"10d"`` is 10 × dim, ``"30"`` is 30."""
    return int(text[:-1]) * dim if text.endswith("d") else int(text)


def run_one(p: TestFunction, method: str, budget: int, seed: int) -> dict:
    """One seeded run: f − f* at the design returned (the closed form), simulations, wall and CPU seconds."""
    t0, c0 = time.perf_counter(), time.process_time()
    row = {"function": p.name, "dim": p.dim, "method": method, "budget": budget, "seed": seed, "raised": ""}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = minimize(p, budget, method=method, seed=seed, options=OPTIONS.get(method))
        x = np.asarray(r.x, dtype=float)
        fun = float(p(x[None, :])[0]) if np.all(np.isfinite(x)) else math.inf
        row.update(error=fun - p.f_min, nfev=int(r.nfev))
    except Exception as exc:  # a peer that raises is a result of the benchmark
        row.update(error=math.inf, nfev=0, raised=repr(exc)[:200])
    row["seconds"], row["cpu_s"] = time.perf_counter() - t0, time.process_time() - c0
    return row


def key(method: str, function: str, budget: int, seed: int) -> str:
    return f"{method}|{function}|{budget}|{seed}"


def load(path: Path) -> dict[str, dict]:
    return json.loads(path.read_text()) if path.exists() else {}


def aligned(p: TestFunction) -> TestFunction:
    """The valley ``p`` with R = Q = I: its axes along the variables, as a perfectly learned rotation would make it
    for a model with one length-scale per variable (the same shift, f* and box)."""
    p.rotation = p.second_rotation = np.eye(p.dim)
    p.name = f"{p.name}{ALIGNED}"
    return p


def run_grid(functions: list[str], budgets: list[str], methods: list[str], seeds: int, path: Path,
             axis_aligned: bool = False) -> None:
    """Every run not yet in the cache, method by method (so a part of the grid ends with whole cells)."""
    cache = load(path)
    for method in methods:
        for name in functions:
            p = aligned(SUITE[name]()) if axis_aligned else SUITE[name]()
            for b in budgets:
                budget = budget_of(b, p.dim)
                for seed in range(seeds):
                    k = key(method, p.name, budget, seed)
                    if k in cache:
                        continue
                    cache[k] = row = run_one(p, method, budget, seed)
                    tmp = path.with_suffix(".tmp")
                    tmp.write_text(json.dumps(cache, indent=0))
                    tmp.replace(path)  # a run killed mid-write leaves the previous cache whole
                    raised = f" RAISED {row['raised']}" if row["raised"] else ""
                    print(f"{p.name:26s} {method:16s} {budget:4d} seed {seed}: f - f* {row['error']:.4g} "
                          f"({row['seconds']:.1f} s, {row['nfev']} sims){raised}", flush=True)


def table(path: Path, methods: list[str], functions: list[str] | None = None) -> str:
    """Markdown: one row per (function, d, budget), the median f − f* of each method (seeds in brackets when fewer
    than the most of any cell), the best peer, and whether ``auto`` is at most the best peer's median."""
    rows = list(load(path).values())
    cells: dict[tuple, dict[str, list[float]]] = {}
    for r in rows:
        if functions and r["function"] not in functions:
            continue
        cells.setdefault((r["dim"], r["function"], r["budget"]), {}).setdefault(r["method"], []).append(r["error"])
    most = max((len(v) for c in cells.values() for v in c.values()), default=0)
    peers = [m for m in methods if m != "auto"]
    lines = ["| function | d | budget | " + " | ".join(methods) + " | best peer | auto <= best peer |",
             "|---" * (len(methods) + 5) + "|"]
    for (dim, name, budget), by_method in sorted(cells.items(), key=lambda c: (c[0][0], c[0][1], c[0][2])):
        med = {m: statistics.median(v) for m, v in by_method.items() if m in methods}
        texts = []
        for m in methods:
            if m not in med:
                texts.append("-")
                continue
            n = len(by_method[m])
            texts.append(f"{med[m]:.3g}" + (f" ({n})" if n < most else ""))
        ran = [m for m in peers if m in med]
        best = min(ran, key=lambda m: med[m]) if ran else None
        verdict = "-" if best is None or "auto" not in med else ("yes" if med["auto"] <= med[best] else "no")
        lines.append(f"| {name} | {dim} | {budget} | " + " | ".join(texts) +
                     f" | {best or '-'} | {verdict} |")
    return "\n".join(lines)


def header() -> str:
    load1, load5, _ = os.getloadavg()
    return (f"command: {' '.join(shlex.quote(a) for a in sys.argv)}\n"
            f"machine: {platform.node()}, {os.cpu_count()} cores (nproc {len(os.sched_getaffinity(0))}), "
            f"load {load1:.2f} / {load5:.2f} (1 / 5 min), Python {platform.python_version()}, "
            f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kinds", nargs="+", default=KINDS, choices=KINDS, help="valleys (default all five)")
    ap.add_argument("--dims", type=int, nargs="+", default=[3, 6, 10], choices=[3, 6, 10])
    ap.add_argument("--functions", nargs="+", choices=sorted(SUITE), help="suite functions instead of the valleys")
    ap.add_argument("--budgets", nargs="+", default=["10d", "30d"], help="10d = 10 x the dimension, or a number")
    ap.add_argument("--methods", nargs="+", default=["auto", *PEERS])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--cache", default="bench_valleys.json")
    ap.add_argument("--suite-bar", action="store_true", help="auto, GPSampler and BoTorch at 30 on the 3-D/4-D suite")
    ap.add_argument("--table", action="store_true", help="only print the table of --cache")
    ap.add_argument("--aligned", action="store_true",
                    help="the valleys with R = Q = I (what a perfectly learned rotation would give)")
    args = ap.parse_args()
    if args.aligned and (args.functions or args.suite_bar):
        ap.error("--aligned takes the valleys only (--kinds, --dims), not --functions or --suite-bar")
    if args.suite_bar:
        args.functions = args.functions or SUITE_BAR
        if args.budgets == ap.get_default("budgets"):
            args.budgets = ["30"]
        if args.methods == ap.get_default("methods"):
            args.methods = ["auto", "optuna_gp", "botorch_qlognei"]
    functions = args.functions or [f"valley_{k}{d}" for d in args.dims for k in args.kinds]
    print(header(), flush=True)
    if not args.table:
        run_grid(functions, args.budgets, args.methods, args.seeds, Path(args.cache), args.aligned)
    if args.aligned:
        functions = [f + ALIGNED for f in functions]
    print("\nmedian f - f* over the seeds (the count in brackets where a cell has fewer seeds than the others)")
    print(table(Path(args.cache), args.methods, functions))


if __name__ == "__main__":
    main()
