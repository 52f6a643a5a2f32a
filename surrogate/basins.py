"""Distinct local minima of a field sampled on a tensor grid: the basins a multimodal model proposes.

The exhaustive search returns one point, the model's global minimum; on a multimodal landscape the model's second or
third minimum may be the true global one (the blend across lines is only accurate to about one line spacing).  This
module lists every grid point no larger than its 3^d − 1 neighbours (a discrete local minimum), best first, and thins
them so that no two kept minima are closer than a given radius: one representative per basin.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import minimum_filter

from mechopt.surrogate.errors import SurrogateError


@dataclass(frozen=True, eq=False)
class Minima:
    """Distinct local minima of a field, best first.

    Attributes
    ----------
    x : (m, d) array
        Their locations (caller's units).
    value : (m,) array
        Field values there.
    """

    x: np.ndarray
    value: np.ndarray

    def __len__(self) -> int:
        return int(self.value.size)


def tensor_grid(lower: np.ndarray, upper: np.ndarray, n_per_axis: int) -> tuple[list[np.ndarray], np.ndarray]:
    """Axes and points (n_per_axis^d, d) of a tensor grid of the box [lower, upper] (bounds included)."""
    lo = np.asarray(lower, dtype=float).reshape(-1)
    hi = np.asarray(upper, dtype=float).reshape(-1)
    if lo.shape != hi.shape or not np.all(hi > lo):
        raise SurrogateError(f"need lower < upper of equal length, got {lo.tolist()} and {hi.tolist()}")
    if int(n_per_axis) < 3:
        raise SurrogateError(f"n_per_axis must be at least 3, got {n_per_axis}")
    axes = [np.linspace(a, b, int(n_per_axis)) for a, b in zip(lo, hi, strict=True)]
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, lo.size)
    return axes, pts


def thin(x: np.ndarray, value: np.ndarray, radius: float, max_count: int | None = None,
         scale: np.ndarray | None = None) -> Minima:
    """Greedy thinning: the best point, then the best point farther than ``radius`` from every kept one, ...

    Parameters
    ----------
    x : (n, d) array
        Points (caller's units).
    value : (n,) array
        Their values; non-finite ones are dropped.
    radius : float
        Smallest distance between kept points, measured in units of ``scale`` (default the caller's units).
    max_count : int, optional
        Most points kept.
    scale : (d,) array, optional
        Per-coordinate divisor of distances (e.g. the box widths, so the radius is a fraction of the box).

    Returns
    -------
    Minima
    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    value = np.asarray(value, dtype=float).reshape(-1)
    if x.shape[0] != value.size:
        raise SurrogateError(f"{x.shape[0]} points but {value.size} values")
    ok = np.isfinite(value)
    x, value = x[ok], value[ok]
    order = np.argsort(value, kind="stable")
    s = np.ones(x.shape[1]) if scale is None else np.asarray(scale, dtype=float)
    kept: list[int] = []
    for j in order:
        if max_count is not None and len(kept) >= max_count:
            break
        if kept and np.min(np.linalg.norm((x[kept] - x[j]) / s, axis=1)) < radius:
            continue
        kept.append(int(j))
    return Minima(x[kept].copy(), value[kept].copy())


def grid_local_minima(values: np.ndarray, axes: list[np.ndarray], radius: float, max_count: int | None = None,
                      scale: np.ndarray | None = None) -> Minima:
    """Distinct discrete local minima of a field on a tensor grid.

    Parameters
    ----------
    values : array of shape (len(axes[0]), ..., len(axes[d − 1]))
        Field values; NaN or +inf mark points outside the region (they are never minima and never block one).
    axes : list of d 1-D arrays
        Grid coordinates per axis (caller's units).
    radius, max_count, scale
        See :func:`thin`.

    Returns
    -------
    Minima
        Grid points no larger than any of their 3^d − 1 neighbours inside the region, thinned, best first.
    """
    v = np.asarray(values, dtype=float)
    if v.shape != tuple(a.size for a in axes):
        raise SurrogateError(f"values of shape {v.shape} do not match the axes {[a.size for a in axes]}")
    v = np.where(np.isfinite(v), v, np.inf)
    # Points outside the region count as +inf neighbours, so a minimum on the region's edge is still a minimum.
    is_min = (v <= minimum_filter(v, size=3, mode="constant", cval=np.inf)) & np.isfinite(v)
    idx = np.nonzero(is_min)
    pts = np.column_stack([axes[k][idx[k]] for k in range(len(axes))])
    return thin(pts, v[idx], radius, max_count, scale)


def field_minima(field: Callable[[np.ndarray], np.ndarray], lower: np.ndarray, upper: np.ndarray,
                 region: Callable[[np.ndarray], np.ndarray] | None, n_per_axis: int, radius: float,
                 max_count: int | None = None) -> Minima:
    """Distinct local minima of ``field`` over the grid points of a box that ``region`` accepts.

    Parameters
    ----------
    field : callable
        ``field(X: (n, d)) -> (n,)`` (vectorised).
    lower, upper : (d,) array
        The box (caller's units).
    region : callable or None
        ``region(X) -> (n,) bool``; None accepts the whole box.
    n_per_axis : int
        Grid points per axis.
    radius : float
        Smallest distance between two kept minima, as a fraction of the box's widths.
    max_count : int, optional
        Most minima returned.

    Returns
    -------
    Minima
    """
    axes, pts = tensor_grid(lower, upper, n_per_axis)
    values = np.full(pts.shape[0], np.inf)
    ok = np.ones(pts.shape[0], dtype=bool) if region is None else np.asarray(region(pts), dtype=bool).reshape(-1)
    if ok.any():
        values[ok] = np.asarray(field(pts[ok]), dtype=float).reshape(-1)
    width = np.asarray(upper, dtype=float) - np.asarray(lower, dtype=float)
    return grid_local_minima(values.reshape([a.size for a in axes]), axes, radius, max_count, width)
