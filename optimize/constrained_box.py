"""The design space of a black-box problem: a box of design variables and cheap constraint margins.

Everything here is cheap (kinematics, no simulation) and is not counted against any budget: mapping designs to and
from the unit cube, constraint margins and violation, feasibility of a batch of designs, feasible Latin-hypercube
samples and the last feasible point of a segment.  :class:`~mechopt.optimize.budget.CountedProblem` adds the
expensive, counted objective on top.

Feasibility is :meth:`DesignProblem.feasible <mechopt.optimize.problem.DesignProblem.feasible>` itself, on the box
and margins seen as a design problem (:class:`BoxProblem`): one vectorised test, ``(n, d) -> (n,)`` booleans, with
the same meaning wherever a design is checked.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.stats import qmc

from mechopt.errors import InputError
from mechopt.optimize.problem import DesignProblem, Variable

__all__ = ["BoxProblem", "ConstrainedBox", "checked_bounds"]

MarginFunction = Callable[[np.ndarray], np.ndarray]


def checked_bounds(bounds: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
    """A box as a float array of shape (d, 2), finite, with low < high in every row.

    Raises
    ------
    InputError
        One line naming what is wrong with ``bounds``.
    """
    try:
        box = np.asarray(bounds, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"bounds must be numbers, got {bounds!r:.80}") from None
    if box.ndim != 2 or box.shape[1] != 2 or box.shape[0] < 1:
        raise InputError(f"bounds must have shape (d, 2), got {box.shape}")
    if not np.all(np.isfinite(box)) or np.any(box[:, 1] <= box[:, 0]):
        raise InputError(f"bounds must be finite with low < high, got {box.tolist()}")
    return box


class BoxProblem(DesignProblem):
    """A box and a margins function as a :class:`~mechopt.optimize.problem.DesignProblem` (variables ``x0``,
    ``x1``, ..., constraints ``g0``, ``g1``, ...), for its feasibility test.

    Parameters
    ----------
    bounds : sequence of (low, high) pairs or array of shape (d, 2)
        Box of the design space, in the variables' units.
    constraints : callable, optional
        ``constraints(x) -> array`` of margins, feasible when all are ``>= 0``.
    vectorized_constraints : bool, default False
        ``constraints`` accepts an array ``(n, d)`` and returns ``(n, m)``; otherwise it is called design by design.

    Notes
    -----
    The number of margins is learned from one call at the box's centre the first time it is needed.
    """

    name = "box"

    def __init__(self, bounds: Sequence[Sequence[float]] | np.ndarray, constraints: MarginFunction | None = None, *,
                 vectorized_constraints: bool = False) -> None:
        box = checked_bounds(bounds)
        self.variables = tuple(Variable(f"x{i}", float(lo), float(hi)) for i, (lo, hi) in enumerate(box))
        self._function = constraints
        self._vectorized = bool(vectorized_constraints)
        self._names: tuple[str, ...] | None = None if constraints is not None else ()

    @property
    def constraints(self) -> tuple[str, ...]:  # type: ignore[override]
        """``g0``, ``g1``, ... one name a margin."""
        if self._names is None:
            count = self.margins(self.bounds.mean(axis=1)[None, :]).shape[1]
            self._names = tuple(f"g{j}" for j in range(count))
        return self._names

    def margins(self, X: np.ndarray) -> np.ndarray:
        """Margins of designs X (n, d), shape (n, m); NaN where the function gave NaN."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if self._function is None:
            return np.zeros((X.shape[0], 0))
        if self._vectorized:
            return np.asarray(self._function(X), dtype=float).reshape(X.shape[0], -1)
        rows = [np.atleast_1d(np.asarray(self._function(x), dtype=float)).ravel() for x in X]
        return np.array(rows, dtype=float).reshape(X.shape[0], -1)


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

    Attributes
    ----------
    space : BoxProblem
        The box and margins as a design problem: its :meth:`~BoxProblem.feasible` is the feasibility test.

    Raises
    ------
    InputError
        If ``bounds`` is not of shape (d, 2), finite, with low < high.
    """

    def __init__(
        self,
        bounds: Sequence[Sequence[float]] | np.ndarray,
        constraints: Callable[[np.ndarray], np.ndarray] | None = None,
        *,
        vectorized_constraints: bool = False,
    ) -> None:
        box = checked_bounds(bounds)
        self.space = BoxProblem(box, constraints, vectorized_constraints=vectorized_constraints)
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

    def feasible(self, X: np.ndarray) -> np.ndarray:
        """Which designs lie in the box and satisfy every constraint margin (NaN margins count as violated).

        Parameters
        ----------
        X : ndarray, shape (n, d) or (d,)
            Designs (one design is a batch of one).

        Returns
        -------
        ndarray of bool, shape (n,)
            :meth:`DesignProblem.feasible <mechopt.optimize.problem.DesignProblem.feasible>` of :attr:`space`; a
            design with a non-finite coordinate (a method's failed step) is infeasible.
        """
        X = np.array(X, dtype=float, ndmin=2)
        finite = np.all(np.isfinite(X), axis=1)
        if finite.all():
            return self.space.feasible(X)
        ok = np.zeros(X.shape[0], dtype=bool)
        if finite.any():
            ok[finite] = self.space.feasible(X[finite])
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
            good = X[self.feasible(X)]
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
            if self.feasible(inside + mid * (outside - inside))[0]:
                lo = mid
            else:
                hi = mid
        return inside + lo * (outside - inside)

