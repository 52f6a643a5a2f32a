"""The methods' own computing time (not the simulators'), per method, dimension and budget: the plan's table.

Each run is :func:`mechopt.minimize` in-process (one worker) on a test function of the suite whose evaluation costs
microseconds, so the wall time is the method's own: its model fits, searches and proposals.  The figure kept is the
sampler's ``method_s`` (wall time outside the simulations).  The table it writes, ``studies/method_time.json``, is
read by the plan of ``mechopt study`` (:mod:`mechopt.studies.method_time`) to add the method's time to the
simulations' (a re-run with every simulation in the store costs that time alone).

Run: ``nice -n 10 python benchmarks/bench_method_time.py`` (about 15 min on 2 busy cores), or, e.g.,
``python benchmarks/bench_method_time.py --methods auto --dims 2 3 --budgets 60 --no-write``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import statistics
import sys
import time
import warnings
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mechopt import minimize  # noqa: E402
from mechopt.studies.benchmark_functions import SUITE  # noqa: E402
from mechopt.studies.method_time import TABLE_FILE  # noqa: E402

#: A test function of each dimension (their evaluations cost microseconds).
FUNCTIONS = {2: "branin", 3: "hartmann3", 4: "hartmann4", 6: "hartmann6"}
METHODS = ("auto", "sparse", "sparse-global", "differential_evolution", "nelder_mead")


def method_seconds(method: str, dim: int, budget: int, seeds: list[int]) -> float | None:
    """Median over ``seeds`` of the method's own seconds on the dimension's function; None where it does not run."""
    if method in ("sparse", "sparse-global") and dim > 4:
        return None
    times = []
    for seed in seeds:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = minimize(SUITE[FUNCTIONS[dim]](), budget=budget, method=method, seed=seed, workers=1)
        times.append(float(result["method_s"]))
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--dims", nargs="+", type=int, default=sorted(FUNCTIONS))
    parser.add_argument("--budgets", nargs="+", type=int, default=[60, 200])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1])
    parser.add_argument("--no-write", action="store_true", help=f"print only; do not write {TABLE_FILE.name}")
    args = parser.parse_args()
    rows: list[dict] = []
    start = time.perf_counter()
    # Every method at the smallest budget first: a long run stopped early still has a row for each.
    for budget in args.budgets:
        for dim in args.dims:
            for method in args.methods:
                seconds = method_seconds(method, dim, budget, args.seeds)
                if seconds is None:
                    continue
                rows.append({"method": method, "dim": dim, "budget": budget, "seconds": round(seconds, 3)})
                print(f"{method:24s} d={dim}  budget {budget:4d}: {seconds:8.2f} s of its own computing", flush=True)
                if not args.no_write:  # after each row, so that a stopped run keeps what it measured
                    write_table(rows, args.seeds)
    print(f"{len(rows)} rows in {time.perf_counter() - start:.0f} s; " +
          ("not written" if args.no_write else f"written: {TABLE_FILE}"))


def write_table(rows: list[dict], seeds: list[int]) -> None:
    """The table as :mod:`mechopt.studies.method_time` reads it, with its command, date and machine."""
    table = {"command": "python benchmarks/bench_method_time.py " + " ".join(sys.argv[1:]),
             "date": datetime.date.today().isoformat(), "cores": os.cpu_count(),
             "load_average_1min": round(os.getloadavg()[0], 1),
             "note": "median over seeds of minimize(...)['method_s'], in-process, on a function costing microseconds",
             "seeds": seeds, "rows": rows}
    TABLE_FILE.write_text(json.dumps(table, indent=1) + "\n")


if __name__ == "__main__":
    main()
