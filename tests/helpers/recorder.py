"""An objective that logs its own calls and their feasibility, independently of CountedProblem (shared by the
baseline tests: what a method asked for is checked here, not by the accounting under test)."""

from __future__ import annotations

import numpy as np


class Recorder:
    """Objective with its own call counter and feasibility log."""

    def __init__(self, f, margins, box: np.ndarray) -> None:
        self.f, self.margins, self.box = f, margins, np.asarray(box, dtype=float)
        self.xs: list[np.ndarray] = []
        self.values: list[float] = []
        self.feasible: list[bool] = []

    def is_feasible(self, x: np.ndarray) -> bool:
        x = np.asarray(x, dtype=float)
        return bool(np.all(x >= self.box[:, 0]) and np.all(x <= self.box[:, 1]) and np.all(self.margins(x) >= 0.0))

    def __call__(self, x: np.ndarray) -> float:
        self.xs.append(np.array(x, dtype=float))
        self.feasible.append(self.is_feasible(x))
        self.values.append(self.f(x))
        return self.values[-1]

    @property
    def calls(self) -> int:
        return len(self.xs)
