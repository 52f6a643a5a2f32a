"""The default method (``method="auto"``: expected hypervolume improvement / constrained EI) against the
multi-objective peers on the suite of ``studies/multi_objective_functions.py``, side by side at equal budgets.

Score: the hypervolume of the feasible non-dominated designs a run evaluated, each objective normalised to
z = (f − ideal) / (nadir − ideal) with the ideal and nadir of the problem's true front, reference point z = 1.1 in
every objective, the same for every method.
For the default method the returned designs (``result.x``) are re-simulated and any broken limit counted.

Every run appends one JSON line to ``--out``; runs already there are skipped, so the benchmark resumes, and
``--table`` prints the table from the file.  The loops run budget → seed → problem → method, so a run cut short
still has every method side by side on the seeds it finished.

Run, e.g.::

    nice -n 10 python benchmarks/bench_pareto.py --budgets 50 200 --seeds 10 --out bench_pareto.jsonl
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

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mechopt import minimize  # noqa: E402
from mechopt.optimize.baselines.multi_objective_peers import MULTI_OBJECTIVE_PEERS  # noqa: E402
from mechopt.optimize.pareto import front_mask, hypervolume, normalisation  # noqa: E402
from mechopt.studies.multi_objective_functions import MULTI_OBJECTIVE_SUITE, FrontProblem  # noqa: E402

METHODS = ("auto", *MULTI_OBJECTIVE_PEERS)


def score(p: FrontProblem, F: np.ndarray, G: np.ndarray) -> tuple[float, int]:
    """Normalised hypervolume of the feasible front of evaluations F (n, k), G (n, m), and its size."""
    ok = np.all(np.isfinite(F), axis=1)
    if G.size:
        ok &= p.limit_spec.met(G)
    F = F[ok]
    if not F.shape[0]:
        return 0.0, 0
    front = F[front_mask(F)]
    return hypervolume(front, normalisation(front, p.ideal, p.nadir)), int(front.shape[0])


def run_one(p: FrontProblem, method: str, budget: int, seed: int) -> dict:
    """One seeded run; an exception is recorded (``raised``), not propagated."""
    row = {"problem": p.name, "method": method, "budget": budget, "seed": seed}
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            broken = 0
            if method == "auto":
                r = minimize(p, budget, seed=seed)
                F, G = r.simulated["F"], r.simulated["G"]
                row["method_s"] = float(r.method_s)
                for x in np.atleast_2d(r.x):  # re-simulated: every returned design must meet every limit
                    out = p.evaluate(x)
                    broken += int(not p.limit_spec.met(p.limit_spec.values(out)[None, :])[0])
            else:
                run = MULTI_OBJECTIVE_PEERS[method](p, budget, seed)
                _, F, G = run.arrays()
        hv, n_front = score(p, F, G)
        row.update(hv=hv, front=n_front, nfev=int(F.shape[0]), broken=broken, raised="")
    except Exception as exc:  # a peer that raises is a result of the benchmark
        row.update(hv=0.0, front=0, nfev=0, broken=0, raised=repr(exc)[:200])
    row.update(wall_s=time.perf_counter() - t0, cpu_s=time.process_time() - c0)
    return row


def table(rows: list[dict]) -> str:
    """Median normalised hypervolume (seeds) per problem, budget and method; the default's method time."""
    cells: dict[tuple, list[dict]] = {}
    for r in rows:
        cells.setdefault((r["problem"], r["budget"], r["method"]), []).append(r)
    methods = [m for m in METHODS if any(key[2] == m for key in cells)]
    head = ("| problem | budget | " + " | ".join(methods)
            + " | auto >= every peer | auto s/sim (method wall; CPU of the whole run) |")
    lines = [head, "|" + "---|" * (len(methods) + 4)]
    for prob, budget in sorted({(k[0], k[1]) for k in cells}, key=lambda t: (t[1], t[0])):
        med = {}
        texts = []
        for m in methods:
            rs = cells.get((prob, budget, m), [])
            if not rs:
                texts.append("-")
                continue
            med[m] = statistics.median(r["hv"] for r in rs)
            fails = sum(bool(r["raised"]) for r in rs)
            texts.append(f"{med[m]:.4f} ({len(rs)}{', ' + str(fails) + ' raised' if fails else ''})")
        auto_rs = cells.get((prob, budget, "auto"), [])
        beats = "-" if "auto" not in med else ("yes" if all(med["auto"] >= v for v in med.values()) else "no")
        per_sim = (statistics.median(r.get("method_s", math.nan) / budget for r in auto_rs) if auto_rs else math.nan)
        cpu = statistics.median(r["cpu_s"] / budget for r in auto_rs) if auto_rs else math.nan
        broken = sum(r.get("broken", 0) for r in auto_rs)
        lines.append(f"| {prob} | {budget} | " + " | ".join(texts) + f" | {beats} | {per_sim:.3f}; {cpu:.3f}"
                     + (f", {broken} broken" if broken else "") + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--problems", nargs="+", default=sorted(MULTI_OBJECTIVE_SUITE))
    ap.add_argument("--methods", nargs="+", default=list(METHODS))
    ap.add_argument("--budgets", nargs="+", type=int, default=[50, 200])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--out", default="bench_pareto.jsonl")
    ap.add_argument("--table", action="store_true", help="print the table of --out and stop")
    args = ap.parse_args(argv)
    out = Path(args.out)
    rows = [json.loads(line) for line in out.read_text().splitlines()] if out.is_file() else []
    if not args.table:
        done = {(r["problem"], r["method"], r["budget"], r["seed"]) for r in rows}
        for budget in args.budgets:
            for seed in range(args.seeds):
                for name in args.problems:
                    for method in args.methods:
                        if (name, method, budget, seed) in done:
                            continue
                        row = run_one(MULTI_OBJECTIVE_SUITE[name](), method, budget, seed)
                        rows.append(row)
                        with out.open("a") as fh:
                            fh.write(json.dumps(row) + "\n")
                        print(f"{name} {method} {budget} seed {seed}: hv {row['hv']:.4f} "
                              f"({row['wall_s']:.1f} s){' ' + row['raised'] if row['raised'] else ''}", flush=True)
    print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
