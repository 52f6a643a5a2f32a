"""The designs a problem allows: its discrete variables' grids, integers and catalogues, as a mixin of
:class:`~mechopt.optimize.problem.DesignProblem`.

Every method proposes in the box as if all variables were continuous and the problem moves the proposal to the
nearest allowed design (:meth:`AllowedDesigns.snap`) before anything is simulated or stored.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mechopt.optimize.variable import Variable
from mechopt.runs.sample_record import KEY_DECIMALS

__all__ = ["AllowedDesigns"]


class AllowedDesigns:
    """Mixin: the allowed designs of a problem with ``variables`` (a tuple of :class:`Variable`)."""

    variables: tuple[Variable, ...] = ()

    @property
    def discrete(self) -> np.ndarray:
        """(d,) bool: which variables allow only some values (a grid, an integer, a catalogue)."""
        return np.array([v.discrete for v in self.variables], dtype=bool)

    @property
    def design_count(self) -> int | None:
        """How many distinct designs the box holds when every variable is discrete, else None."""
        counts = [v.count for v in self.variables]
        return None if None in counts else math.prod(counts)

    def snap(self, X: Any, clip: bool = True) -> np.ndarray:
        """Designs (n, d) or (d,) moved to their nearest allowed design (discrete variables clipped to the box and
        rounded to their grid, integers or catalogue; continuous ones unchanged).  ``clip=False``: a grid or the
        integers continue beyond the bounds (:meth:`Variable.snap`), for designs a method samples outside the
        box on purpose."""
        X = np.asarray(X, dtype=float)
        out = np.array(X, dtype=float, ndmin=2, copy=True)
        for j, v in enumerate(self.variables):
            if v.discrete:
                out[:, j] = v.snap(out[:, j], clip)
        return out.reshape(X.shape)

    def on_grid(self, X: Any) -> np.ndarray:
        """(n,) bool: designs whose discrete variables hold allowed values."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        mask = self.discrete
        if not mask.any():
            return np.ones(len(X), dtype=bool)
        tol = 10.0 ** -(KEY_DECIMALS - 1)
        return np.all(np.abs(self.snap(X)[:, mask] - X[:, mask]) <= tol, axis=1)

    def space_text(self, budget: int | None = None) -> str:
        """One line for a plan: the discrete variables' kinds and the number of distinct designs when finite, and
        whether ``budget`` simulations cover them; empty when every variable is continuous."""
        if not self.discrete.any():
            return ""
        kinds = ", ".join(f"{v.name} {v.describe_kind()}" for v in self.variables if v.discrete)
        count = self.design_count
        if count is None:
            return f"discrete variables: {kinds}; every design simulated lies on them"
        covered = (f"; the budget of {budget} covers them all: the method may enumerate the space"
                   if budget is not None and budget >= count else "")
        return f"discrete variables: {kinds}; {count:,} distinct designs{covered}"
