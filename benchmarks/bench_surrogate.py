"""Benchmark of the surrogate mathematics: fitting 7 lines x 90 samples, and 10 million masked model evaluations.

Run with ``python studies/bench_surrogate.py`` (from the repository root, or with mechopt installed).  Prints a
table of medians over several runs; the anchor is the paper's 10,000,000 evaluations of the blended model in 3 min
on a six-core i7-9850H.  Targets: evaluation <= 0.2 s and fitting <= 50 ms on a 2-core machine.
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mechopt.surrogate import LinePlan, SparseExponentialModel, exhaustive_search, grid_minimum, hull_grid  # noqa: E402

PAPER_DELTA = np.array([0.000, 0.920, 0.503])  # the paper's Δ in U = (|OA|, |BC|, |AB|) coordinates, mm
PAPER_ORIGIN = np.array([31.000, 257.859, 72.705])
NODES = np.array([[0, 0], [12, 0], [6, 10], [-6, 10], [-12, 0], [-6, -10], [4, -5.0]])  # mm in the normal plane
N_SAMPLES = 90
RUNS = 7


def _median_time(fn, runs: int = RUNS) -> float:
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def _data(plan: LinePlan, noise: float, seed: int = 0) -> list[tuple[np.ndarray, np.ndarray]]:
    """A smooth positive torque-like field: five exponential terms per line with (p, q)-dependent weights."""
    rng = np.random.default_rng(seed)
    lam = np.array([-0.06, -0.02, 0.015, 0.03 + 0.02j, 0.03 - 0.02j])
    out = []
    ks = np.arange(N_SAMPLES)
    for i in range(plan.n_lines):
        P, d = plan.coordinates(plan.points(i, ks))
        p, q = P[:, 0] / 12, P[:, 1] / 10
        w = np.stack([2 + p, 1 + 0.5 * q * q, 0.3 + 0.1 * p * q, 0.05 * (1 + 1j) * (1 + q), 0.05 * (1 - 1j) * (1 + q)])
        values = (w.T * np.exp(np.outer(d - 45, lam))).sum(axis=1).real
        out.append((ks, values * (1 + noise * rng.standard_normal(ks.size))))
    return out


def main() -> None:
    E = LinePlan(PAPER_DELTA, PAPER_ORIGIN, np.zeros((1, 3))).normal_basis
    plan = LinePlan(PAPER_DELTA, PAPER_ORIGIN, NODES @ E)
    clean, noisy = _data(plan, 0.0), _data(plan, 1e-4)

    rows = []
    t_fit5 = _median_time(lambda: SparseExponentialModel(order=5).fit(plan, clean))
    rows.append(("fit 7 lines x 90 samples, order 5", t_fit5, "<= 0.050 s"))
    t_fit_auto = _median_time(lambda: SparseExponentialModel().fit(plan, noisy))
    auto = SparseExponentialModel().fit(plan, noisy)
    rows.append(("fit 7 x 90, automatic order, 1e-4 noise", t_fit_auto, f"<= 0.050 s; orders {auto.orders}"))

    model = SparseExponentialModel(order=5).fit(plan, clean)
    # Warm up numba (compiles or loads the cache) on a small grid.
    small = hull_grid(model, n_points=10_000)
    grid_minimum(model, small, np.ones(small.n_points, bool))

    # Size the grid so that about 10 million points pass the mask (a spherical exclusion plus a half-space).
    probe = hull_grid(model, n_points=200_000)
    centre = plan.from_coordinates([[2.0, 1.0]], [45.0])[0]

    def feasible(X: np.ndarray) -> np.ndarray:
        return (np.linalg.norm(X - centre, axis=1) > 8.0) & (X[:, 0] < centre[0] + 9.0)

    def mask_of(grid) -> np.ndarray:
        out = np.empty(grid.n_points, bool)
        for s in range(0, grid.n_points, 2_000_000):
            e = min(s + 2_000_000, grid.n_points)
            out[s:e] = feasible(plan.from_coordinates(*grid.coordinates(s, e)))
        return out

    fraction = mask_of(probe).mean()
    t_grid = time.perf_counter()
    grid = hull_grid(model, n_points=int(10_000_000 / fraction))
    t_grid = time.perf_counter() - t_grid
    mask = mask_of(grid)
    n_eval = int(mask.sum())
    t_eval = _median_time(lambda: grid_minimum(model, grid, mask))
    rows.append(
        (f"masked evaluation + argmin, {n_eval / 1e6:.2f} M of {grid.n_points / 1e6:.2f} M", t_eval, "<= 0.200 s")
    )
    rows.append(("build the hull grid (once per search)", t_grid, ""))

    # Side by side: plain numpy model.predict on 1 M random points, scaled to the same count.
    X = plan.from_coordinates(*grid.coordinates(0, 1_000_000))
    t_np = _median_time(lambda: model.predict(X), runs=3) * n_eval / 1_000_000
    rows.append(("model.predict (numpy, scattered), same count", t_np, f"ratio {t_np / t_eval:.0f}x"))

    res = exhaustive_search(model, feasible=feasible, n_points=int(10_000_000 / fraction))
    rows.append(
        (
            "exhaustive_search end to end (numpy predicate)",
            res.timings["total"],
            " ".join(f"{k}={v:.3f}" for k, v in res.timings.items() if k != "total"),
        )
    )

    print(f"surrogate benchmark — {os.cpu_count()} cores, median of {RUNS} runs unless noted")
    print(f"{'what':58s} {'seconds':>9s}  note")
    for what, sec, note in rows:
        print(f"{what:58s} {sec:9.4f}  {note}")
    print(f"paper anchor: 1e7 evaluations in 180 s on 6 cores -> {180 / t_eval * n_eval / 1e7:.0f}x faster here")


if __name__ == "__main__":
    main()
