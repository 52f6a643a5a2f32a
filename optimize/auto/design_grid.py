"""The allowed designs of a problem with discrete variables, in the unit cube the default method works in.

The Gaussian process models the objective over the box as if every variable were continuous (a relaxation); the
acquisition is then maximised over allowed designs only: candidates are moved to their nearest allowed design
before they are scored, a gradient polish of the relaxed acquisition is followed by a choice among the allowed
designs around its end (scored by the acquisition), and local moves on a discrete variable go to its neighbouring
values.  When the space holds few designs (:data:`ENUMERATE_MAX`) every one of them
is a candidate.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["ENUMERATE_MAX", "DesignGrid", "unique_rows"]

#: Largest number of designs whose whole list is searched by the acquisition (a score of each at every step).
ENUMERATE_MAX = 10_000
#: Allowed values on each side of the centre that a local move of a discrete variable reaches.
NEIGHBOUR_RADIUS = 2


class DesignGrid:
    """The allowed values of each variable, in unit-cube coordinates (None for a continuous variable).

    Parameters
    ----------
    lower, upper : (d,) array_like
        The box, in the variables' units.
    allowed : sequence of (ndarray or None)
        Increasing allowed values of each discrete variable, in its unit; None for a continuous one.  At least one
        must be given.
    """

    def __init__(self, lower: Any, upper: Any, allowed: Sequence[np.ndarray | None]) -> None:
        self.lo = np.asarray(lower, dtype=float)
        self.width = np.asarray(upper, dtype=float) - self.lo
        self.values = [None if a is None else (np.asarray(a, dtype=float) - self.lo[j]) / self.width[j]
                       for j, a in enumerate(allowed)]
        self.mask = np.array([a is not None for a in self.values], dtype=bool)
        if not self.mask.any():
            raise ValueError("a DesignGrid needs at least one discrete variable")

    @classmethod
    def of(cls, problem: Any) -> DesignGrid | None:
        """The grid of a :class:`~mechopt.optimize.problem.DesignProblem`, None when every variable is continuous."""
        variables = tuple(problem.variables)
        if not any(v.discrete for v in variables):
            return None
        b = np.asarray(problem.bounds, dtype=float)
        return cls(b[:, 0], b[:, 1], [v.allowed() if v.discrete else None for v in variables])

    @property
    def all_discrete(self) -> bool:
        """Whether every variable is discrete (the space is finite)."""
        return bool(self.mask.all())

    @property
    def count(self) -> int | None:
        """Number of designs of the box when every variable is discrete, else None."""
        return math.prod(len(a) for a in self.values) if self.all_discrete else None

    @property
    def step(self) -> np.ndarray:
        """(d,) smallest distance between neighbouring allowed values (unit cube); 0 on a continuous variable."""
        return np.array([0.0 if a is None else float(np.min(np.diff(a))) for a in self.values])

    def _index(self, j: int, u: np.ndarray) -> np.ndarray:
        a = self.values[j]
        i = np.clip(np.searchsorted(a, u), 1, len(a) - 1)
        return np.where(u - a[i - 1] <= a[i] - u, i - 1, i)

    def snap(self, U: np.ndarray) -> np.ndarray:
        """Designs U (n, d) of the unit cube moved to their nearest allowed design (clipped to the cube first)."""
        U = np.clip(np.array(U, dtype=float, ndmin=2), 0.0, 1.0)
        for j in np.flatnonzero(self.mask):
            U[:, j] = self.values[j][self._index(j, U[:, j])]
        return U

    def enumerate(self, lo: np.ndarray | None = None, hi: np.ndarray | None = None) -> np.ndarray:
        """Every allowed design inside the box [lo, hi] of the unit cube (a finite space only), (m, d)."""
        if not self.all_discrete:
            raise ValueError("only a space of discrete variables can be enumerated")
        lo = np.zeros(self.mask.size) if lo is None else lo
        hi = np.ones(self.mask.size) if hi is None else hi
        axes = [a[(a >= lo[j] - 1e-12) & (a <= hi[j] + 1e-12)] for j, a in enumerate(self.values)]
        if any(a.size == 0 for a in axes):
            return np.zeros((0, self.mask.size))
        return np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, self.mask.size)

    def neighbourhood(self, centre: np.ndarray, radius: int = NEIGHBOUR_RADIUS) -> np.ndarray:
        """Designs that move the discrete variables of ``centre`` by up to ``radius`` allowed values each (the
        continuous ones kept), the centre's own allowed design included, (m, d)."""
        c = self.snap(centre)[0]
        axes = []
        for j, a in enumerate(self.values):
            if a is None:
                axes.append(np.array([c[j]]))
            else:
                i = int(self._index(j, np.array([c[j]]))[0])
                axes.append(a[max(0, i - radius): i + radius + 1])
        return np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, c.size)

    def candidates(self, C: np.ndarray, lo: np.ndarray, hi: np.ndarray, centre: np.ndarray) -> np.ndarray:
        """The allowed designs to score instead of the continuous candidates ``C`` in the box [lo, hi]: every design
        of a small finite space, else ``C`` snapped, with the centre's neighbourhood; distinct, in the box."""
        count = self.count
        if count is not None and count <= ENUMERATE_MAX:
            return self.enumerate(lo, hi)
        S = np.vstack([self.snap(C), self.neighbourhood(centre)])
        inside = np.all((S >= lo - 1e-12) & (S <= hi + 1e-12), axis=1)
        return unique_rows(S[inside])


def unique_rows(U: np.ndarray) -> np.ndarray:
    """Distinct rows of U in the order they first appear."""
    if U.shape[0] < 2:
        return U
    _, first = np.unique(U, axis=0, return_index=True)
    return U[np.sort(first)]
