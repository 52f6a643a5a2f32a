"""Flexible slider-crank (paper 004): time per simulation of both engines and their agreement.

Run: ``python benchmarks/bench_flexible.py [--repeats 5] [--designs 5]``.  Prints the median wall time per
simulation of the modal KED model and of Exudyn (ANCF cable), measured side by side, and for a handful of designs
(the target and seeded random ones in the study's box) the largest deviation of Exudyn from the modal model,
relative to the range of each response: V, A, and D both against the modal model with the axial-force stiffening
(the like-for-like physics) and against the paper's linear model without it.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from mechopt.sim.flexible_slider_crank import FlexibleSliderCrank, simulate


def _rel(x: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.abs(x - ref)) / np.ptp(ref))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--designs", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    ref = FlexibleSliderCrank.from_mm(50.0, 350.0, 1.53075)
    simulate(ref, "modal")  # numba compile / cache load
    simulate(ref, "exudyn")  # Exudyn import
    print(f"flexible slider-crank, {ref.n_samples} samples over {ref.t_end} s, {ref.n_elements} elements, "
          f"{ref.n_modes} modes, beta = {ref.beta} s")
    for engine, p in (("modal (paper)", ref), ("modal + stiffening", ref.with_(axial_stiffening=True)),
                      ("exudyn", ref)):
        name = "exudyn" if engine == "exudyn" else "modal"
        times = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            simulate(p, name)
            times.append(time.perf_counter() - t0)
        print(f"  {engine:20s} median {1e3 * statistics.median(times):8.1f} ms per simulation "
              f"(min {1e3 * min(times):.1f}, {args.repeats} runs)")

    rng = np.random.default_rng(args.seed)
    designs = [(50.0, 350.0, 1.53075)] + [tuple(rng.uniform([20, 200, 1], [80, 500, 2])) for _ in
                                           range(args.designs - 1)]
    print("agreement, max |exudyn - modal| / range:")
    print(f"  {'l2 mm':>7s} {'l3 mm':>7s} {'h mm':>6s} | {'V':>8s} {'A':>8s} {'D stiff':>8s} {'D paper':>8s} | "
          f"{'D peak mm':>9s}")
    for l2, l3, h in designs:
        p = FlexibleSliderCrank.from_mm(l2, l3, h)
        ex = simulate(p, "exudyn")
        st = simulate(p.with_(axial_stiffening=True), "modal")
        pa = simulate(p, "modal")
        print(f"  {l2:7.2f} {l3:7.2f} {h:6.3f} | {_rel(ex.V, st.V):8.1e} {_rel(ex.A, st.A):8.1e} "
              f"{_rel(ex.D, st.D):8.1e} {_rel(ex.D, pa.D):8.1e} | {np.max(np.abs(ex.D)) * 1e3:9.3f}")


if __name__ == "__main__":
    main()
