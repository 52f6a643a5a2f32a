"""The default method (``method="auto"``) and the shipped peers side by side on the multimodal suite, each run
through :func:`mechopt.minimize` (store, sampler, failure handling: what a user gets).

Every run appends one JSON line to ``--out`` (function, method, budget, seed, best value, gap, evaluations,
failures, seconds, whether it raised); runs already in that file are not repeated, so a table can be built over
several invocations (``--table`` prints it from the file alone).  Printed per cell: median gap (f_best − f_min) in %
of the function's range, median best value, seeds in the global basin, median seconds per run.  Then, for each
peer, how often a run of the default ends lower than a run of the peer and the two-sided Mann-Whitney p-value of
the two samples of gaps: whether a difference of medians is more than seed luck.  (A seed's number gives two
methods unrelated random draws, so runs are compared as two samples, not in pairs.)

Run, e.g.::

    python benchmarks/bench_default.py --functions hartmann3 hartmann4 --budgets 30 \\
        --methods auto smt_ego --seeds 10 --out bench_default.jsonl
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.stats import mannwhitneyu

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mechopt import minimize  # noqa: E402
from mechopt.optimize.methods import DEFAULT_METHOD  # noqa: E402
from mechopt.studies.benchmark_functions import SUITE, TestFunction  # noqa: E402

#: Peers named by the issue: SMT EGO at small budgets, the library optimisers at large ones.
PEERS = ("smt_ego", "nevergrad_ngopt", "pymoo_de", "optuna_tpe", "optuna_cmaes")


def run_one(p: TestFunction, method: str, budget: int, seed: int) -> dict:
    """One seeded run; an exception is recorded (``raised``), not propagated."""
    t0, c0 = time.perf_counter(), time.process_time()
    row = {"function": p.name, "dim": p.dim, "method": method, "budget": budget, "seed": seed}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = minimize(p, budget, method=method, seed=seed)
        x = np.asarray(r.x, dtype=float)
        # The closed form at the design returned: a noisy function's simulated value is partly its noise.
        fun = float(p(x[None, :])[0]) if np.all(np.isfinite(x)) else math.inf
        hit = bool(np.all(np.isfinite(x)) and math.isfinite(fun) and p.in_global_basin(x))
        gap = 100.0 * p.gap(fun) if math.isfinite(fun) else math.inf
        row.update(fun=fun, observed=float(r.fun), gap=gap, nfev=int(r.nfev),
                   nfailed=int(r.get("nfailed", 0)), hit=hit, plan=r.get("plan", ""), raised="")
    except Exception as exc:  # a peer that raises is a result of the benchmark
        row.update(fun=math.inf, gap=math.inf, nfev=0, nfailed=0, hit=False, plan="", raised=repr(exc)[:200])
    # CPU time of this process (the method's own compute, the closed-form evaluations and the store): on a
    # machine shared with other jobs the wall time overstates it.
    row["seconds"], row["cpu_s"] = time.perf_counter() - t0, time.process_time() - c0
    return row


def load(path: Path) -> list[dict]:
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def run_all(args: argparse.Namespace) -> None:
    out = Path(args.out)
    done = {(r["function"], r["method"], r["budget"], r["seed"]) for r in load(out)}
    for name in args.functions:
        p = SUITE[name]()
        for budget in args.budgets:
            for method in args.methods:
                for seed in range(args.seeds):
                    if (name, method, budget, seed) in done:
                        continue
                    row = run_one(p, method, budget, seed)
                    with out.open("a") as fh:
                        fh.write(json.dumps(row) + "\n")
                    print(f"{name:18s} {method:16s} {budget:4d} seed {seed}: gap {row['gap']:.4g} % "
                          f"({row['seconds']:.1f} s){' RAISED ' + row['raised'] if row['raised'] else ''}",
                          flush=True)


def table(path: Path, methods: list[str] | None = None) -> None:
    rows = load(path)
    cells: dict[tuple, list[dict]] = {}
    for r in rows:
        cells.setdefault((r["dim"], r["function"], r["budget"]), []).append(r)
    methods = methods or sorted({r["method"] for r in rows}, key=lambda m: (m != DEFAULT_METHOD, m))
    print("median gap % of range | median best value | seeds in the global basin / seeds | median s/run; "
          "'raised' counts runs that raised")
    print(f"{'function':18s} {'d':>2s} {'budget':>6s} " + " ".join(f"{m:>34s}" for m in methods))
    for (dim, name, budget), group in sorted(cells.items()):
        line = [f"{name:18s} {dim:2d} {budget:6d}"]
        for m in methods:
            runs = [r for r in group if r["method"] == m]
            if not runs:
                line.append(f"{'-':>34s}")
                continue
            raised = sum(bool(r["raised"]) for r in runs)
            gap, fun = statistics.median(r["gap"] for r in runs), statistics.median(r["fun"] for r in runs)
            secs, hits = statistics.median(r["seconds"] for r in runs), sum(r["hit"] for r in runs)
            text = f"{gap:8.3g} {fun:9.4g} {hits:2d}/{len(runs):<2d} {secs:5.1f}" + (f" r{raised}" if raised else "")
            line.append(f"{text:>34s}")
        print(" ".join(line))


def rank_test(path: Path, reference: str = "auto") -> None:
    """Per cell and peer: the probability that a run of ``reference`` ends with a smaller gap than a run of the
    peer (ties count half; the Mann-Whitney U statistic over n·m) and the two-sided Mann-Whitney p-value."""
    cells: dict[tuple, dict[str, list[float]]] = {}
    for r in load(path):
        cells.setdefault((r["dim"], r["function"], r["budget"]), {}).setdefault(r["method"], []).append(r["gap"])
    lines = []
    for (dim, name, budget), by_method in sorted(cells.items()):
        ref = by_method.get(reference)
        for peer, gaps in sorted(by_method.items()):
            if peer == reference or not ref:
                continue
            # A run that raised (an infinite gap) or found nothing (NaN) ranks last; the test needs finite values.
            worst = 2.0 * max([abs(g) for g in ref + gaps if math.isfinite(g)] + [1.0])
            a = np.nan_to_num(np.array(ref, dtype=float), nan=worst, posinf=worst)
            b = np.nan_to_num(np.array(gaps, dtype=float), nan=worst, posinf=worst)
            test = mannwhitneyu(a, b, alternative="two-sided")
            share = float(test.statistic) / (a.size * b.size)
            lines.append(f"{name:18s} {dim:2d} {budget:6d} {peer:>16s} {1.0 - share:13.2f} {test.pvalue:10.3g}")
    if lines:
        print(f"\n{reference} against each peer: P({reference} ends lower) over all pairs of runs, Mann-Whitney p")
        print(f"{'function':18s} {'d':>2s} {'budget':>6s} {'peer':>16s} {'P(lower)':>13s} {'p':>10s}")
        print("\n".join(lines))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--functions", nargs="+", default=list(SUITE), choices=list(SUITE))
    ap.add_argument("--methods", nargs="+", default=["auto", *PEERS])
    ap.add_argument("--budgets", type=int, nargs="+", default=[30])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--out", default="bench_default.jsonl")
    ap.add_argument("--table", action="store_true", help="only print the table of --out")
    args = ap.parse_args()
    if not args.table:
        run_all(args)
    table(Path(args.out), None if args.table else args.methods)
    rank_test(Path(args.out))


if __name__ == "__main__":
    main()
