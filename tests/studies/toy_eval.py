"""Toy simulators for the sampling tests: deterministic, instant or slept, picklable top-level functions.

Worker processes (local pools and Dask workers) import this module by name, so the tests put this folder on
``sys.path`` before importing it; child processes inherit that path.
"""

from __future__ import annotations

import os
import time

import numpy as np
from mechopt.errors import InfeasibleDesignError
from mechopt.studies.store import design_key

#: A design with this |OA| (mm) makes :func:`toy_eval` raise a plain error.
FAIL_OA = 13.0
FAIL_MESSAGE = "toy solver diverged"


def toy_eval(design: tuple[float, float, float]) -> dict:
    """Closed-form stand-in for the simulator.

    Infeasible when |AB| > |OA| + |BC| (the toy cannot assemble), failing with ``RuntimeError`` when
    ``oa == FAIL_OA``, otherwise smooth torques in N·m plus numpy-typed extras (to exercise JSON conversion).
    """
    oa, ab, bc = design
    if oa == FAIL_OA:
        raise RuntimeError(f"{FAIL_MESSAGE}\nat oa={oa}")  # two lines on purpose: records keep one
    if ab > oa + bc:
        raise InfeasibleDesignError(f"cannot assemble: |AB| = {ab:g} mm > |OA| + |BC| = {oa + bc:g} mm")
    t_rms = 1e-3 * (oa**2 + 0.5 * ab + 0.25 * bc)
    return {
        "t_rms": t_rms,
        "t_max": 2.0 * t_rms + 1e-2 * oa,
        "n_steps": np.int64(100),
        "torque_head": np.array([0.0, t_rms, -t_rms]),
    }


def counting_eval(design: tuple[float, float, float], counter: str, delay: float = 0.0) -> dict:
    """:func:`toy_eval` that first appends the design key to ``counter`` (one line per call) and sleeps.

    A single ``O_APPEND`` write of a short line is atomic, so concurrent workers never interleave lines.
    """
    fd = os.open(counter, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        os.write(fd, (design_key(design) + "\n").encode())
    finally:
        os.close(fd)
    if delay:
        time.sleep(delay)
    return toy_eval(design)


def malformed_eval(design: tuple[float, float, float]) -> object:
    """Returns something unusable for some designs: a float, no t_max, a NaN t_rms, a non-JSON extra."""
    oa = design[0]
    if oa == 1.0:
        return 3.5
    if oa == 2.0:
        return {"t_rms": 1.0}
    if oa == 3.0:
        return {"t_rms": float("nan"), "t_max": 1.0}
    if oa == 4.0:
        return {"t_rms": 1.0, "t_max": 1.0, "handle": object()}
    return {"t_rms": 1.0, "t_max": 2.0}


def random_designs(n: int, seed: int) -> list[tuple[float, float, float]]:
    """``n`` distinct designs (mm) rounded to 0.01 mm, a few of them infeasible for :func:`toy_eval`."""
    rng = np.random.default_rng(seed)
    lo, hi = np.array([15.0, 60.0, 40.0]), np.array([50.0, 110.0, 90.0])
    pts = np.round(rng.uniform(lo, hi, size=(n, 3)), 2)
    return [tuple(float(x) for x in p) for p in pts]
