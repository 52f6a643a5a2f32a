"""The design space of a black-box problem: a box of design variables and cheap constraint margins.

Everything here is cheap (kinematics, no simulation) and is not counted against any budget: mapping designs to and
from the unit cube, constraint margins and violation, feasibility of one design or of a batch, feasible
Latin-hypercube samples and the last feasible point of a segment.  :class:`~mechopt.optimize.budget.CountedProblem`
adds the expensive, counted objective on top.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.stats import qmc

__all__ = ["ConstrainedBox"]


class ConstrainedBox:
    """Box of design variables with cheap constraint margins (feasible when all are ``>= 0``).

    Parameters
    ----------
    bounds : sequence of (low, high) pairs or array of shape (d, 2)
        Box of the design space, in the variables' units; a design outside the box is infeasible.
    constraints : callable, optional
        ``constraints(x) -> array`` of margins, feasible when all are ``>= 0``.  Cheap, not counted.
    vectorized_constraints : bool, default False
        ``constraints`` accepts an array ``(n, d)`` and returns ``(n, m)``; speeds up dense feasibility checks.

    Raises
    ------
    ValueError
        If ``bounds`` is not of shape (d, 2), finite, with low < high.
    """

    def __init__(
        self,
        bounds: Sequence[Sequence[float]] | np.ndarray,
        constraints: Callable[[np.ndarray], np.ndarray] | None = None,
        *,
        vectorized_constraints: bool = False,
    ) -> None:
        box = np.asarray(bounds, dtype=float)
        if box.ndim != 2 or box.shape[1] != 2 or box.shape[0] < 1:
            raise ValueError(f"bounds must have shape (d, 2), got {box.shape}")
        if not np.all(np.isfinite(box)) or np.any(box[:, 1] <= box[:, 0]):
            raise ValueError("bounds must be finite with low < high")
        self._constraints = constraints
        self.lower = box[:, 0].copy()
        self.upper = box[:, 1].copy()
        self.vectorized_constraints = bool(vectorized_constraints)

    # ------------------------------------------------------------------ geometry
    @property
    def dim(self) -> int:
        """Number of design variables."""
        return self.lower.size

    @property
    def span(self) -> np.ndarray:
        """Width of the box per variable."""
        return self.upper - self.lower

    @property
    def bounds(self) -> np.ndarray:
        """Box as an array of shape (d, 2)."""
        return np.column_stack([self.lower, self.upper])

    @property
    def has_constraints(self) -> bool:
        """Whether constraint margins beyond the box were given."""
        return self._constraints is not None

    def to_unit(self, x: np.ndarray) -> np.ndarray:
        """Map designs to the unit cube of the box (local solvers work there so tolerances are scale-free)."""
        return (np.asarray(x, dtype=float) - self.lower) / self.span

    def from_unit(self, u: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`to_unit`; a point of the closed unit cube maps exactly into the box."""
        u = np.asarray(u, dtype=float)
        x = self.lower + u * self.span
        # Rounding of lower + 1.0 * span may land one ulp outside the box, which would make a face infeasible.
        inside = (u >= 0.0) & (u <= 1.0)
        return np.where(inside, np.clip(x, self.lower, self.upper), x)

    def clip(self, x: np.ndarray) -> np.ndarray:
        """Project a design onto the box."""
        return np.clip(np.asarray(x, dtype=float), self.lower, self.upper)

    # ------------------------------------------------------------------ constraints (cheap, not counted)
    def margins(self, x: np.ndarray) -> np.ndarray:
        """Constraint margins of one design (``>= 0`` feasible), without the box; NaN margins count as violated.

        Parameters
        ----------
        x : ndarray, shape (d,)

        Returns
        -------
        ndarray, shape (m,)
            Empty when the problem has no constraints.
        """
        if self._constraints is None:
            return np.zeros(0)
        g = np.atleast_1d(np.asarray(self._constraints(np.asarray(x, dtype=float)), dtype=float)).ravel()
        # A NaN margin comes from a failed kinematic solve: the design must not pass as feasible.
        return np.where(np.isnan(g), -1.0, g)

    def violation(self, x: np.ndarray) -> float:
        """Total violation: sum of box excess and of negative margins (0 for a feasible design).

        Parameters
        ----------
        x : ndarray, shape (d,)

        Returns
        -------
        float
        """
        x = np.asarray(x, dtype=float)
        box = np.sum(np.maximum(self.lower - x, 0.0)) + np.sum(np.maximum(x - self.upper, 0.0))
        return float(box + np.sum(np.maximum(-self.margins(x), 0.0)))

    def feasible(self, x: np.ndarray) -> bool:
        """Whether a design lies in the box and satisfies every constraint margin.

        Parameters
        ----------
        x : ndarray, shape (d,)

        Returns
        -------
        bool
        """
        x = np.asarray(x, dtype=float)
        if np.any(x < self.lower) or np.any(x > self.upper):
            return False
        return self._constraints is None or bool(np.all(self.margins(x) >= 0.0))

    def feasible_many(self, X: np.ndarray) -> np.ndarray:
        """Feasibility of a batch of designs.

        Parameters
        ----------
        X : ndarray, shape (n, d)

        Returns
        -------
        ndarray of bool, shape (n,)
        """
        X = np.atleast_2d(np.asarray(X, dtype=float))
        inside = np.all((X >= self.lower) & (X <= self.upper), axis=1)
        if self._constraints is None or X.shape[0] == 0:
            return inside
        if self.vectorized_constraints:
            g = np.asarray(self._constraints(X), dtype=float).reshape(X.shape[0], -1)
            return inside & np.all(g >= 0.0, axis=1)  # NaN >= 0 is False, as wanted
        ok = inside.copy()
        for i in np.flatnonzero(inside):
            ok[i] = bool(np.all(self.margins(X[i]) >= 0.0))
        return ok

    def sample_feasible(self, n: int, rng: np.random.Generator, *, max_batches: int = 50) -> np.ndarray:
        """Latin-hypercube designs in the box, keeping the feasible ones (cheap rejection sampling).

        Parameters
        ----------
        n : int
            Number of feasible designs wanted.
        rng : numpy.random.Generator
            Source of randomness (the method's seeded generator).
        max_batches : int, default 50
            Number of LHS batches of size ``max(n, 16)`` tried before giving up.

        Returns
        -------
        ndarray, shape (k, d)
            ``k <= n`` feasible designs, fewer only when the feasible region is too small to be hit.
        """
        if n <= 0:
            return np.zeros((0, self.dim))
        found: list[np.ndarray] = []
        total = 0
        batch = max(n, 16)
        for _ in range(max_batches):
            X = self.from_unit(qmc.LatinHypercube(self.dim, rng=rng).random(batch))
            good = X[self.feasible_many(X)]
            found.append(good)
            total += good.shape[0]
            if total >= n:
                break
        return np.concatenate(found)[:n] if found else np.zeros((0, self.dim))

    def boundary_point(self, inside: np.ndarray, outside: np.ndarray, *, n_bisect: int = 52) -> np.ndarray:
        """Last feasible point of the segment from a feasible to an infeasible design (cheap bisection).

        Parameters
        ----------
        inside : ndarray, shape (d,)
            Feasible design.
        outside : ndarray, shape (d,)
            Infeasible design.
        n_bisect : int, default 52
            Bisection steps (52 reach the resolution of a double on the segment).

        Returns
        -------
        ndarray, shape (d,)
            A feasible design on the segment, as close to the first constraint crossing as the bisection gets.
        """
        inside = np.asarray(inside, dtype=float)
        outside = np.asarray(outside, dtype=float)
        lo, hi = 0.0, 1.0
        for _ in range(n_bisect):
            mid = 0.5 * (lo + hi)
            if self.feasible(inside + mid * (outside - inside)):
                lo = mid
            else:
                hi = mid
        return inside + lo * (outside - inside)

