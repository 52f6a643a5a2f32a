"""Constraint margins of path-synthesis slider-cranks (>= 0 feasible), vectorised over designs.

* ``grashof``: a2 − a1 − |a5| >= 0.  The rod reaches the slider line at every crank angle, |a5 − a1 sin φ| <= a2,
  exactly when a1 + |a5| <= a2: the crank turns fully (the paper's Grashof condition for the slider-crank) and the
  two branches K = ±1 are two separate circuits.
* ``bar_ratio``: m·min − max >= 0 over the lengths a1, a2, |a3|, |a4| (paper example 1: "a maximum 3:1 ratio between
  the longest and shortest bar", m = 3).

Margins are in the unit of the lengths.  A design whose crank cannot turn has a negative ``grashof`` margin: margins
never raise.

The design problem declares both as smooth pieces (:func:`margins`): ``grashof`` as a2 − a1 − a5 >= 0 and
a2 − a1 + a5 >= 0, ``bar_ratio`` as m|b_i| − |b_j| >= 0 for every ordered pair of bars.  The feasible set is the same
(the minimum of the pieces is the margin above), but a method that linearises its constraints (SLSQP, Gauss-Newton
with linearised margins) is misled by the kink of |a5| at a5 = 0 and by the switch of the shortest or longest bar;
each piece is linear in the variables wherever the bars keep their signs.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BAR_RATIO_PAIRS", "CONSTRAINTS", "GRASHOF", "bar_ratio_margin", "grashof_margin", "margins"]

#: The ordered pairs (i, j) of the bars a1, a2, a3, a4 (columns 0..3) of the bar-ratio pieces m|b_i| − |b_j|.
BAR_RATIO_PAIRS = tuple((i, j) for i in range(4) for j in range(4) if i != j)
#: Names of the Grashof pieces, then of the bar-ratio pieces, in the order of :func:`margins`' columns.
GRASHOF = ("grashof_a5_up", "grashof_a5_down")
CONSTRAINTS = (*GRASHOF, *(f"bar_ratio_a{i + 1}_a{j + 1}" for i, j in BAR_RATIO_PAIRS))


def grashof_margin(X: np.ndarray) -> np.ndarray:
    """a2 − a1 − |a5| of designs X (n, 8): >= 0 when the crank turns fully."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    return X[:, 1] - X[:, 0] - np.abs(X[:, 4])


def bar_ratio_margin(X: np.ndarray, ratio: float = 3.0) -> np.ndarray:
    """ratio · min − max of the lengths a1, a2, |a3|, |a4| of designs X (n, 8): >= 0 within the ratio."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    bars = np.abs(X[:, :4])
    return ratio * bars.min(axis=1) - bars.max(axis=1)


def margins(X: np.ndarray, max_ratio: float | None = None) -> np.ndarray:
    """The smooth pieces of the margins of designs X (n, 8): :data:`GRASHOF`, and the bar-ratio pieces when
    ``max_ratio`` is given (names in :data:`CONSTRAINTS`).

    Parameters
    ----------
    X : (n, 8) array_like
        Designs (a1, ..., a8).
    max_ratio : float, optional
        Largest allowed ratio of the longest to the shortest of a1, a2, |a3|, |a4|; None: no such constraint.

    Returns
    -------
    (n, 2) or (n, 14) ndarray
        One column per piece (lengths); their minimum over the Grashof columns is :func:`grashof_margin`, over the
        bar-ratio columns :func:`bar_ratio_margin`.
    """
    X = np.atleast_2d(np.asarray(X, dtype=float))
    base = X[:, 1] - X[:, 0]
    cols = [base - X[:, 4], base + X[:, 4]]
    if max_ratio is not None:
        bars = np.abs(X[:, :4])
        cols += [max_ratio * bars[:, i] - bars[:, j] for i, j in BAR_RATIO_PAIRS]
    return np.stack(cols, axis=1)
