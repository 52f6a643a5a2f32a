"""Parallel sampling lines and their coordinates (paper Section 4, Eq. 10–12 and 16).

A :class:`LinePlan` describes ``l`` parallel lines in R^d, all parallel to a direction Δ.  The sample points are

    X(i, k) = origin + k Δ + δ(i),        k integer,

so consecutive samples on a line are ‖Δ‖ apart.  Every point X gets coordinates (P, d):

* ``d(X) = <Δ, X − origin> / ‖Δ‖²``, the position along Δ in units of one sample step, so that
  ``d(X(i, k)) = k + d(δ(i))`` (the paper's Algorithm 1 definition of d);
* ``P(X) = E (X − origin)``, the coordinates of the projection of X onto the normal plane through ``origin`` in an
  orthonormal basis E (rows) of that plane.

The paper characterises a line by two of the three quantities of Eq. 16 (``p = Δ_v u − Δ_u v``,
``q = Δ_w u − Δ_u w``); with the paper's own Δ = (0, 0.920, 0.503) these two are proportional (Δ_u = 0), so they
cannot tell lines apart.  An orthonormal basis of the normal plane spans the same information and is always well
conditioned; E is built by Gram–Schmidt on the coordinate axes taken in order of increasing |Δ_k|, so for the paper's
Δ the first normal coordinate is simply the u-axis.

All lengths are coordinates in the caller's units; ``d`` is dimensionless (sample steps).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from mechopt.surrogate.errors import SurrogateError

FeasiblePredicate = Callable[[np.ndarray], np.ndarray]


def _as_vector(value: Any, name: str, dim: int | None = None) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim != 1 or arr.size == 0:
        raise SurrogateError(f"{name} must be a non-empty 1-D vector, got shape {arr.shape}")
    if dim is not None and arr.size != dim:
        raise SurrogateError(f"{name} must have {dim} components, got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise SurrogateError(f"{name} must be finite, got {arr.tolist()}")
    return arr


def _frozen(arr: np.ndarray) -> np.ndarray:
    arr = np.array(arr, copy=True)
    arr.setflags(write=False)
    return arr


def normal_basis(direction: np.ndarray) -> np.ndarray:
    """Orthonormal basis of the hyperplane orthogonal to ``direction``.

    Parameters
    ----------
    direction : (d,) array
        Non-zero direction Δ (coordinates in the caller's units).

    Returns
    -------
    (d - 1, d) array
        Rows are orthonormal and orthogonal to Δ.  Deterministic: Gram–Schmidt on the coordinate axes in order of
        increasing ``|Δ_k|`` (the axes least aligned with Δ give the best-conditioned projections).  For d = 3 the
        second row is ``Δ̂ × e₁`` so (e₁, e₂, Δ̂) is right-handed.
    """
    u = np.asarray(direction, dtype=float)
    u = u / np.linalg.norm(u)
    dim = u.size
    rows: list[np.ndarray] = []
    for axis in np.argsort(np.abs(u), kind="stable"):
        if len(rows) == dim - 1:
            break
        v = np.zeros(dim)
        v[axis] = 1.0
        # Two Gram-Schmidt passes keep the rows orthonormal to machine precision.
        for _ in range(2):
            v -= (v @ u) * u
            for r in rows:
                v -= (v @ r) * r
        norm = np.linalg.norm(v)
        if norm > 1e-8:
            rows.append(v / norm)
    if dim == 3:
        rows[1] = np.cross(u, rows[0])
    return np.array(rows).reshape(dim - 1, dim)


class LineHull:
    """Convex hull of sampled line segments, with a vectorised membership test.

    Parameters
    ----------
    points : (n, d) array
        Segment end points (coordinates in the caller's units).

    Raises
    ------
    SurrogateError
        If the points do not span a d-dimensional volume (e.g. all lines lie in one plane).
    """

    def __init__(self, points: np.ndarray) -> None:
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[0] < pts.shape[1] + 1:
            raise SurrogateError(
                f"the hull needs at least d+1 = {pts.shape[-1] + 1} segment end points, got {pts.shape[0]}"
            )
        try:
            hull = ConvexHull(pts)
        except QhullError as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else "degenerate input"
            raise SurrogateError(
                f"the hull of the sampled segments is flat in {pts.shape[1]}-D (lines coplanar?): {first}"
            ) from exc
        self.points = pts
        self.vertices = pts[hull.vertices]
        self.equations = hull.equations  # rows (n, b): n·x + b <= 0 inside, |n| = 1
        self.volume = float(hull.volume)
        self.scale = float(np.max(np.ptp(pts, axis=0)))

    def contains(self, X: np.ndarray, tol: float = 1e-9, chunk: int = 1_000_000) -> np.ndarray:
        """Whether points lie in the hull (boundary included).

        Parameters
        ----------
        X : (n, d) or (d,) array
            Points, coordinates in the caller's units.
        tol : float
            Tolerance relative to the hull's extent, so sample points on the boundary count as inside.
        chunk : int
            Number of points tested per block, bounding the temporary memory.

        Returns
        -------
        (n,) bool array
        """
        pts = np.atleast_2d(np.asarray(X, dtype=float))
        normals = self.equations[:, :-1]
        offsets = self.equations[:, -1] - tol * self.scale
        out = np.empty(pts.shape[0], dtype=bool)
        for start in range(0, pts.shape[0], chunk):
            block = pts[start : start + chunk]
            out[start : start + chunk] = np.all(block @ normals.T + offsets <= 0.0, axis=1)
        return out


@dataclass(frozen=True, eq=False)
class LinePlan:
    """``l`` parallel lines ``origin + k Δ + δ(i)`` in R^d (coordinates in the caller's units).

    Parameters
    ----------
    direction : (d,) array
        Δ, the step between consecutive samples of a line; must be non-zero.
    origin : (d,) array
        Point from which the lines are offset (the paper translates the domain so this is 0).
    offsets : (l, d) array
        δ(i), the shift of line i; δ(0) = 0 is allowed (the paper's convention), not required.  Offsets may have a
        component along Δ; it only shifts that line's sample indices.
    k_ranges : (l, 2) int array, optional
        Inclusive sampled index range ``[k_lo, k_hi]`` of each line, used by the hull; set by the planner or by
        :meth:`with_k_ranges`.
    """

    direction: np.ndarray
    origin: np.ndarray
    offsets: np.ndarray
    k_ranges: np.ndarray | None = None
    _basis: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        direction = _as_vector(self.direction, "direction Δ")
        dim = direction.size
        if dim < 2:
            raise SurrogateError(f"lines need dimension d >= 2, got d = {dim}")
        norm = float(np.linalg.norm(direction))
        if norm == 0.0:
            raise SurrogateError(f"direction Δ must be non-zero, got {direction.tolist()}")
        origin = _as_vector(self.origin, "origin", dim)
        offsets = np.asarray(self.offsets, dtype=float)
        if offsets.ndim == 1 and offsets.size == dim:
            offsets = offsets[None, :]
        if offsets.ndim != 2 or offsets.shape[1] != dim or offsets.shape[0] == 0:
            raise SurrogateError(f"offsets must have shape (l, {dim}) with l >= 1, got {offsets.shape}")
        if not np.all(np.isfinite(offsets)):
            raise SurrogateError("offsets δ(i) must be finite, got a NaN or infinite entry")
        object.__setattr__(self, "direction", _frozen(direction))
        object.__setattr__(self, "origin", _frozen(origin))
        object.__setattr__(self, "offsets", _frozen(offsets))
        object.__setattr__(self, "_basis", _frozen(normal_basis(direction)))
        if self.k_ranges is not None:
            object.__setattr__(self, "k_ranges", _frozen(self._check_k_ranges(self.k_ranges)))

    def _check_k_ranges(self, k_ranges: Any) -> np.ndarray:
        kr = np.asarray(k_ranges)
        if kr.shape != (self.n_lines, 2):
            raise SurrogateError(f"k_ranges must have shape ({self.n_lines}, 2), got {kr.shape}")
        if not np.all(np.isfinite(kr.astype(float))) or np.any(kr != np.round(kr)):
            raise SurrogateError(f"k_ranges must be integers, got {kr.tolist()}")
        kr = kr.astype(np.int64)
        if np.any(kr[:, 1] < kr[:, 0]):
            raise SurrogateError(f"k_ranges need k_lo <= k_hi on every line, got {kr.tolist()}")
        return kr

    # ----------------------------------------------------------------------------------------------- basics
    @property
    def dim(self) -> int:
        """Dimension d of the design space."""
        return int(self.direction.size)

    @property
    def n_lines(self) -> int:
        """Number of lines l."""
        return int(self.offsets.shape[0])

    @property
    def spacing(self) -> float:
        """Distance between consecutive samples, ‖Δ‖ (caller's units)."""
        return float(np.linalg.norm(self.direction))

    @property
    def normal_basis(self) -> np.ndarray:
        """(d − 1, d) orthonormal rows spanning the normal plane of Δ (see :func:`normal_basis`)."""
        return self._basis

    def with_k_ranges(self, k_ranges: Any) -> LinePlan:
        """Return a copy of the plan with the sampled index ranges set.

        Parameters
        ----------
        k_ranges : (l, 2) int array
            Inclusive ``[k_lo, k_hi]`` per line.

        Returns
        -------
        LinePlan
        """
        return replace(self, k_ranges=np.asarray(k_ranges))

    def point(self, i: int, k: float) -> np.ndarray:
        """Sample point ``origin + k Δ + δ(i)`` of line ``i`` (caller's units), shape (d,)."""
        return self.points(i, np.array([k], dtype=float))[0]

    def points(self, i: int, ks: Any) -> np.ndarray:
        """Sample points of line ``i`` at indices ``ks`` (integers or reals), shape (len(ks), d)."""
        if not 0 <= int(i) < self.n_lines:
            raise SurrogateError(f"line index must be in [0, {self.n_lines - 1}], got {i}")
        k = np.atleast_1d(np.asarray(ks, dtype=float))
        return self.origin + np.outer(k, self.direction) + self.offsets[int(i)]

    # ------------------------------------------------------------------------------------------ coordinates
    def along(self, X: Any) -> np.ndarray:
        """Paper's ``d(X) = <Δ, X − origin> / ‖Δ‖²`` (sample steps), shape (n,)."""
        pts = np.atleast_2d(np.asarray(X, dtype=float))
        return (pts - self.origin) @ self.direction / self.spacing**2

    def d(self, X: Any) -> np.ndarray:
        """The paper's name for :meth:`along`: ``<Δ, X − origin> / ‖Δ‖²`` (sample steps), shape (n,)."""
        return self.along(X)

    def normal_coordinates(self, X: Any) -> np.ndarray:
        """Coordinates of the projection of X on the normal plane, shape (n, d − 1) (caller's units).

        Constant along every line parallel to Δ; they play the role of the paper's (p, q) of Eq. 16.
        """
        pts = np.atleast_2d(np.asarray(X, dtype=float))
        return (pts - self.origin) @ self._basis.T

    def coordinates(self, X: Any) -> tuple[np.ndarray, np.ndarray]:
        """Both coordinates: ``(P, d)`` with P of shape (n, d − 1) and d of shape (n,)."""
        return self.normal_coordinates(X), self.along(X)

    def from_coordinates(self, P: Any, d: Any) -> np.ndarray:
        """Inverse of :meth:`coordinates`: points ``origin + Eᵀ P + d Δ``, shape (n, d)."""
        P = np.atleast_2d(np.asarray(P, dtype=float))
        d = np.atleast_1d(np.asarray(d, dtype=float))
        return self.origin + P @ self._basis + d[:, None] * self.direction

    def line_nodes(self) -> np.ndarray:
        """Normal-plane coordinates (p_i, q_i) of every line, shape (l, d − 1) (caller's units)."""
        return self.offsets @ self._basis.T

    def line_shifts(self) -> np.ndarray:
        """``d(δ(i))`` relative to the origin, so ``d(X(i, k)) = k + line_shifts()[i]``, shape (l,)."""
        return self.offsets @ self.direction / self.spacing**2

    # ------------------------------------------------------------------------------------------ feasibility
    def feasible_run(self, i: int, feasible: FeasiblePredicate, k_min: int, k_max: int) -> np.ndarray:
        """Longest contiguous run of feasible sample indices on line ``i``.

        A line may enter and leave the feasible region several times; only the longest run of consecutive
        feasible indices is kept because the exponential fit needs equispaced samples.

        Parameters
        ----------
        i : int
            Line index.
        feasible : callable
            ``feasible(X: (n, d) array) -> (n,) bool array``.
        k_min, k_max : int
            Inclusive index range to scan.

        Returns
        -------
        (m,) int array
            Consecutive indices (empty if no point is feasible); ties go to the run with the smallest k.
        """
        if int(k_max) < int(k_min):
            raise SurrogateError(f"need k_min <= k_max, got k_min = {k_min}, k_max = {k_max}")
        ks = np.arange(int(k_min), int(k_max) + 1)
        ok = np.asarray(feasible(self.points(i, ks)), dtype=bool).reshape(-1)
        if ok.size != ks.size:
            raise SurrogateError(f"feasible() must return {ks.size} booleans, got {ok.size}")
        if not ok.any():
            return ks[:0]
        padded = np.concatenate(([False], ok, [False])).astype(np.int8)
        edges = np.flatnonzero(np.diff(padded))
        starts, stops = edges[0::2], edges[1::2]
        best = int(np.argmax(stops - starts))
        return ks[starts[best] : stops[best]]

    # ------------------------------------------------------------------------------------------------ hull
    def _ranges(self, k_ranges: Any | None) -> np.ndarray:
        if k_ranges is not None:
            return self._check_k_ranges(k_ranges)
        if self.k_ranges is None:
            raise SurrogateError("the plan has no k_ranges; pass k_ranges or use plan.with_k_ranges(...)")
        return self.k_ranges

    def segment_ends(self, k_ranges: Any | None = None) -> np.ndarray:
        """End points of the sampled segments, shape (2 l, d): line i gives rows 2i (k_lo) and 2i + 1 (k_hi)."""
        kr = self._ranges(k_ranges)
        ends = [self.points(i, kr[i]) for i in range(self.n_lines)]
        return np.concatenate(ends, axis=0)

    def hull(self, k_ranges: Any | None = None) -> LineHull:
        """Convex hull of the sampled segments (the region where the blended model is valid).

        Parameters
        ----------
        k_ranges : (l, 2) int array, optional
            Inclusive sampled index range per line; defaults to ``self.k_ranges``.

        Returns
        -------
        LineHull
        """
        return LineHull(self.segment_ends(k_ranges))

    def hull_contains(self, X: Any, k_ranges: Any | None = None) -> np.ndarray:
        """Vectorised test whether points lie in the hull of the sampled segments, shape (n,) bool."""
        return self.hull(k_ranges).contains(X)

    # ------------------------------------------------------------------------------------------------ JSON
    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly representation (plain lists)."""
        return {
            "direction": self.direction.tolist(),
            "origin": self.origin.tolist(),
            "offsets": self.offsets.tolist(),
            "k_ranges": None if self.k_ranges is None else self.k_ranges.tolist(),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> LinePlan:
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(
                direction=data["direction"],
                origin=data["origin"],
                offsets=data["offsets"],
                k_ranges=data.get("k_ranges"),
            )
        except KeyError as exc:
            raise SurrogateError(f"line plan dictionary lacks the key {exc.args[0]!r}") from exc
