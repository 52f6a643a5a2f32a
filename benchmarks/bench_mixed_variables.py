"""The default method against the peers on the mixed-variable problems of ``studies/mixed_variable_functions.py``,
side by side at equal budgets.

Every run goes through ``mechopt compare``'s own :func:`~mechopt.studies.comparison.engine.run_one` (the same
:func:`mechopt.minimize`, the same budget and the same score): the gap is ``100 (f / f* − 1)`` per cent of the best
known value f* at the returned design (NaN when no feasible design was found).  Each design simulated is recorded, so
the table also says how many were off their grids (must be 0) and how many repeated a design of the same run (must
be 0).  A peer with a ``max_budget`` in the table of methods (SMT's EGO refits Kriging at every step) is run up to
its ``max_budget`` simulations (``--cap-model`` replaces it, e.g. to run SMT at 100 for a benchmark) and marked "not
run" beyond.

Every run appends one JSON line to ``--out``; runs already there are skipped, so the benchmark resumes, and
``--table`` prints the table from the file.  The loops run budget → seed → problem → method.

Run, e.g.::

    nice -n 10 python benchmarks/bench_mixed_variables.py --budgets 50 100 --seeds 10 --out bench_mixed.jsonl
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mechopt.optimize.methods import DEFAULT_METHOD, METHODS  # noqa: E402
from mechopt.runs.store import design_key  # noqa: E402
from mechopt.studies.comparison.engine import OWN_METHOD, compared_methods, run_one  # noqa: E402
from mechopt.studies.comparison.score import known_truth  # noqa: E402
from mechopt.studies.mixed_variable_functions import MIXED_SUITE  # noqa: E402

#: The peers: the library baselines that declare discrete variables in their own terms (``discrete`` in the table).
PEERS = tuple(name for name, m in compared_methods().items() if m.discrete and not m.own)


def recording(cls: type) -> type:
    """The problem class with every simulated design recorded in ``calls`` (the runs are in-process)."""

    class Recorded(cls):
        def __init__(self) -> None:
            self.calls: list[np.ndarray] = []

        def evaluate(self, x: np.ndarray) -> dict[str, float]:
            self.calls.append(np.array(x, dtype=float))
            return super().evaluate(x)

    Recorded.__name__ = cls.__name__
    return Recorded


def run(name: str, method: str, budget: int, seed: int) -> dict:
    """One seeded run of compare's ``method`` (``mechopt`` is the default method) on problem ``name``."""
    problem = recording(MIXED_SUITE[name])()
    truth = known_truth(problem)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = run_one(problem, truth, method, budget, seed, DEFAULT_METHOD)
    X = np.array(problem.calls).reshape(-1, problem.dim)
    keys = [design_key(tuple(x)) for x in X]
    return {"problem": name, "method": method, "budget": budget, "seed": seed, "value": r.value, "gap": r.gap_pct,
            "nfev": r.nfev, "off_grid": int((~problem.on_grid(X)).sum()) if len(X) else 0,
            "repeats": len(keys) - len(set(keys)), "finished": r.finished, "reason": r.reason,
            "wall_s": time.perf_counter() - t0}


def _cap(method: str, dim: int, cap_model: int | None) -> int | None:
    record = compared_methods().get(method)
    if record is None or record.max_budget is None:
        return None
    return record.max_budget(dim) if cap_model is None else cap_model


def table(rows: list[dict], methods: list[str]) -> str:
    """Markdown table: per problem and budget, each method's median gap, feasible seeds, off-grid and repeated
    simulations, median simulations spent, unfinished runs and median wall time."""
    out = ["| problem | budget | method | median gap % | feasible seeds | median f | off-grid / repeated designs "
           "| simulations (median) | unfinished | median s |", "|---|---|---|---|---|---|---|---|---|---|"]
    for name in MIXED_SUITE:
        for budget in sorted({r["budget"] for r in rows}):
            for method in methods:
                rs = [r for r in rows if r["problem"] == name and r["budget"] == budget and r["method"] == method]
                if not rs:
                    continue
                ok = [r for r in rs if r["finished"] and math.isfinite(r["gap"])]
                gap = statistics.median([r["gap"] for r in ok]) if len(ok) == len(rs) else math.inf
                med = (f"{statistics.median(r['gap'] for r in ok):.3g}" if ok else "—") \
                    + ("" if len(ok) == len(rs) else f" ({len(ok)} of {len(rs)})")
                if math.isinf(gap) and ok:
                    med = f"— (only {len(ok)} of {len(rs)} feasible)"
                value = f"{statistics.median(r['value'] for r in ok):.6g}" if ok else "—"
                bad = f"{sum(r['off_grid'] for r in rs)} / {sum(r['repeats'] for r in rs)}"
                nfev = statistics.median(r["nfev"] for r in rs)
                out.append(f"| {name} | {budget} | {method} | {med} | {len(ok)}/{len(rs)} | {value} | {bad} | "
                           f"{nfev:g} | {sum(not r['finished'] for r in rs)} | "
                           f"{statistics.median(r['wall_s'] for r in rs):.1f} |")
    return "\n".join(out)


def header(argv: list[str]) -> str:
    """The command, the machine and its load."""
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    return (f"command: python benchmarks/bench_mixed_variables.py {' '.join(argv)}\n"
            f"date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; machine: {platform.machine()}, "
            f"{os.cpu_count()} cores, load average {load}; default method {DEFAULT_METHOD!r} "
            f"({METHODS[DEFAULT_METHOD].compare_name}); peers {', '.join(PEERS)}")


def main(argv: list[str] | None = None) -> None:
    """Run the benchmark (resuming ``--out``) and print the table."""
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--budgets", type=int, nargs="+", default=[50, 100])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=0, help="run seeds first-seed .. seeds - 1 (split a long run)")
    ap.add_argument("--problems", nargs="+", default=list(MIXED_SUITE), choices=list(MIXED_SUITE))
    ap.add_argument("--methods", nargs="+", default=[OWN_METHOD, *PEERS])
    ap.add_argument("--cap-model", type=int, default=None,
                    help="largest budget of a peer that has a max_budget (default: that max_budget)")
    ap.add_argument("--out", type=Path, default=Path("bench_mixed.jsonl"))
    ap.add_argument("--table", action="store_true", help="only print the table of --out")
    args = ap.parse_args(argv)
    print(header(argv), flush=True)
    done = [json.loads(line) for line in args.out.read_text().splitlines()] if args.out.is_file() else []
    have = {(r["problem"], r["method"], r["budget"], r["seed"]) for r in done}
    for budget in [] if args.table else args.budgets:
        for seed in range(args.first_seed, args.seeds):
            for name in args.problems:
                dim = MIXED_SUITE[name]().dim
                for method in args.methods:
                    cap = _cap(method, dim, args.cap_model)
                    if (name, method, budget, seed) in have or (cap is not None and budget > cap):
                        continue
                    row = run(name, method, budget, seed)
                    done.append(row)
                    with args.out.open("a") as fh:
                        fh.write(json.dumps(row) + "\n")
                    print(f"  {name} {method} budget {budget} seed {seed}: gap {row['gap']:.3g} %, "
                          f"{row['nfev']} simulations, {row['wall_s']:.1f} s", flush=True)
    rows = [r for r in done if r["problem"] in args.problems and r["budget"] in args.budgets]
    print(f"\nload average at the end: {', '.join(f'{v:.2f}' for v in os.getloadavg())}")
    print(table(rows, args.methods))


if __name__ == "__main__":
    main()
