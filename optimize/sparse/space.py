"""The design space as the sparse model sees it: the problem's box and predicates in the model's coordinates.

The model's coordinates U are the design variables in the order the problem asks for (paper 002 plans the
ventilator over (|OA|, |BC|, |AB|), so its Δ and origin are read in as printed); everywhere else designs keep the
problem's declared order.  The permutation lives here, in one place.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechopt.optimize.problem import DesignProblem

__all__ = ["ModelSpace"]


@dataclass(frozen=True)
class ModelSpace:
    """A problem's box and predicates, in design coordinates X and model coordinates U.

    Parameters
    ----------
    problem : DesignProblem
        The problem.
    """

    problem: DesignProblem

    @property
    def order(self) -> np.ndarray:
        """Index of the design variable behind each model coordinate."""
        order = self.problem.surrogate_order
        return np.arange(self.problem.dim) if order is None else np.asarray(order, dtype=int)

    @property
    def dim(self) -> int:
        """Number of design variables."""
        return self.problem.dim

    @property
    def box(self) -> np.ndarray:
        """(d, 2) bounds in design coordinates."""
        return self.problem.bounds

    def to_u(self, X: np.ndarray) -> np.ndarray:
        """Designs (…, d) -> model coordinates."""
        return np.asarray(X, dtype=float)[..., self.order]

    def from_u(self, U: np.ndarray) -> np.ndarray:
        """Model coordinates (…, d) -> designs."""
        return np.asarray(U, dtype=float)[..., np.argsort(self.order)]

    @property
    def lower_u(self) -> np.ndarray:
        """Lower bounds in model coordinates."""
        return self.to_u(self.box[:, 0])

    @property
    def upper_u(self) -> np.ndarray:
        """Upper bounds in model coordinates."""
        return self.to_u(self.box[:, 1])

    def feasible(self, X: np.ndarray) -> np.ndarray:
        """Designs (n, d) in the box satisfying every constraint."""
        return self.problem.feasible(np.atleast_2d(X))

    def feasible_u(self, U: np.ndarray) -> np.ndarray:
        """:meth:`feasible` in model coordinates."""
        return self.problem.feasible(self.from_u(np.atleast_2d(U)))

    def screen_u(self, U: np.ndarray) -> np.ndarray:
        """The problem's cheaper feasibility screen in model coordinates, for search grids."""
        return np.asarray(self.problem.screen(self.from_u(np.atleast_2d(U))), dtype=bool)

    def sampleable_u(self, U: np.ndarray) -> np.ndarray:
        """Where the model's lines may be simulated, in model coordinates."""
        return np.asarray(self.problem.sampleable(self.from_u(np.atleast_2d(U))), dtype=bool)

    def margins(self, x: np.ndarray) -> np.ndarray:
        """Constraint margins of one design (d,) -> (m,), for local searches."""
        return self.problem.constraint_margins(np.atleast_2d(x))[0]
