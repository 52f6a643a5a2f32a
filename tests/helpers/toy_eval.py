"""Toy design problems for the store and sampling tests: closed forms, picklable, optionally slow and counted.

Worker processes (local pools and Dask workers) import this module by name, so the tests put this folder on
``sys.path`` before importing it; child processes inherit that path.
"""

from __future__ import annotations

import os
import time

import numpy as np

from mechopt.errors import InfeasibleDesignError
from mechopt.optimize.problem import DesignProblem, Variable
from mechopt.runs.store import design_key

#: A design with this first value makes :class:`ToyProblem` raise a plain error.
FAIL_A = 13.0
FAIL_MESSAGE = "toy solver diverged"


def _count(counter: str | None, design: np.ndarray) -> None:
    """Append the design key to ``counter`` (one line per call).

    A single ``O_APPEND`` write of a short line is atomic, so concurrent workers never interleave lines.
    """
    if not counter:
        return
    fd = os.open(counter, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        os.write(fd, (design_key(design) + "\n").encode())
    finally:
        os.close(fd)


class ToyProblem(DesignProblem):
    """Closed-form stand-in for a mechanism: three lengths a, b, c (mm), outputs ``f`` and ``g`` (N·m).

    Infeasible when b > a + c (the toy cannot assemble); fails with ``RuntimeError`` when ``a == fail_a``;
    otherwise ``f = scale · 1e-3 (a² + b/2 + c/4)`` and ``g = 2 f + 1e-2 a``, plus numpy-typed extras (to exercise the
    JSON conversion).

    Parameters
    ----------
    scale : float
        Multiplies ``f``: a setting that changes the outputs, hence the fingerprint.
    delay : float
        Seconds slept per evaluation (a slow simulator); does not change an output.
    counter : str, optional
        File that gets one line per evaluation (the design key), to count calls across processes.
    fail_a : float or None
        First value that makes the evaluator fail (a bug, not a setting: it is not in the fingerprint); None for a
        fixed evaluator.
    """

    name = "toy"
    variables = (
        Variable("a", 10.0, 60.0, "mm"),
        Variable("b", 50.0, 120.0, "mm"),
        Variable("c", 30.0, 100.0, "mm"),
    )
    outputs = ("f", "g")
    objective = "f"

    def __init__(
        self, scale: float = 1.0, delay: float = 0.0, counter: str | None = None, fail_a: float | None = FAIL_A
    ) -> None:
        self.scale = scale
        self.delay = delay
        self.counter = counter
        self.fail_a = fail_a

    def settings(self) -> dict:
        return {"scale": self.scale}

    def evaluate(self, x: np.ndarray) -> dict:
        _count(self.counter, x)
        if self.delay:
            time.sleep(self.delay)
        a, b, c = (float(v) for v in x)
        if a == self.fail_a:
            raise RuntimeError(f"{FAIL_MESSAGE}\nat a={a}")  # two lines on purpose: records keep one
        if b > a + c:
            raise InfeasibleDesignError(f"cannot assemble: b = {b:g} mm > a + c = {a + c:g} mm")
        f = self.scale * 1e-3 * (a**2 + 0.5 * b + 0.25 * c)
        return {"f": f, "g": 2.0 * f + 1e-2 * a, "n_steps": np.int64(100), "head": np.array([0.0, f, -f])}


def expected_outputs(design, scale: float = 1.0) -> dict:
    """What :class:`ToyProblem` stores for a feasible design, computed independently of it (JSON types)."""
    a, b, c = design
    f = scale * 1e-3 * (a**2 + 0.5 * b + 0.25 * c)
    return {"f": f, "g": 2.0 * f + 1e-2 * a, "n_steps": 100, "head": [0.0, f, -f]}


class MalformedProblem(DesignProblem):
    """Returns something unusable for designs (k, 5): keyed by k = 1..6; k = 7 is fine."""

    name = "malformed"
    variables = (Variable("k", 0.0, 10.0), Variable("y", 0.0, 10.0))
    outputs = ("f", "g")
    objective = "f"

    def evaluate(self, x: np.ndarray) -> object:
        k = float(x[0])
        if k == 1.0:
            return 3.5
        if k == 2.0:
            return {"f": 1.0}
        if k == 3.0:
            return {"f": float("nan"), "g": 1.0}
        if k == 4.0:
            return {"f": 1.0, "g": 1.0, "handle": object()}
        if k == 5.0:
            return {"f": "fast", "g": 1.0}
        if k == 6.0:
            return {"f": np.array([1.0, 2.0]), "g": 1.0}
        return {"f": np.float32(1.5), "g": 2, "label": "fine"}


class InterruptingProblem(ToyProblem):
    """:class:`ToyProblem` that raises KeyboardInterrupt (a Ctrl-C) on its ``stop_after + 1``-th evaluation."""

    def __init__(self, stop_after: int) -> None:
        super().__init__()
        self.stop_after = stop_after
        self.calls = 0

    def evaluate(self, x: np.ndarray) -> dict:
        self.calls += 1
        if self.calls > self.stop_after:
            raise KeyboardInterrupt
        return super().evaluate(x)


def random_designs(n: int, seed: int) -> list[tuple[float, float, float]]:
    """``n`` distinct designs (mm) rounded to 0.01 mm, a few of them infeasible for :class:`ToyProblem`."""
    rng = np.random.default_rng(seed)
    lo, hi = np.array([15.0, 60.0, 40.0]), np.array([50.0, 110.0, 90.0])
    pts = np.round(rng.uniform(lo, hi, size=(n, 3)), 2)
    return [tuple(float(x) for x in p) for p in pts]


def calls(counter) -> list[str]:
    """Keys written to a counter file, one per evaluation."""
    return open(counter).read().split() if os.path.exists(counter) else []
