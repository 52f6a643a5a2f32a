"""A small problem with one variable of each kind (continuous, drawing grid, integer, catalogue) and a constraint,
shared by the tests of discrete variables."""

from __future__ import annotations

import numpy as np

from mechopt import DesignProblem, Variable


class MixedBowl(DesignProblem):
    """A quadratic bowl over (x, s, n, d) with the room constraint x + s <= 2.2; every evaluation is recorded in
    ``calls`` (the tests run in-process)."""

    name = "mixed_bowl"
    variables = (Variable("x", 0.0, 1.0), Variable("s", 0.0, 2.0, step=0.1), Variable("n", 1, 8, integer=True),
                 Variable("d", values=(0.5, 0.63, 0.8, 1.0)))
    constraints = ("room",)
    outputs = ("f",)
    objective = "f"

    def __init__(self) -> None:
        self.calls: list[tuple[float, ...]] = []

    def margins(self, X: np.ndarray) -> np.ndarray:
        return (2.2 - X[:, 0] - X[:, 1])[:, None]

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        self.calls.append(tuple(float(v) for v in x))
        f = (x[0] - 0.31) ** 2 + (x[1] - 1.27) ** 2 + 0.1 * (x[2] - 4.4) ** 2 + (x[3] - 0.7) ** 2 + 0.2 * x[0] * x[3]
        return {"f": float(f)}
