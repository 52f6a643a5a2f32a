"""Exhaustive search of the blended model on a dense grid of the hull ∩ feasible region, then a local polish.

The grid lives in the plan's coordinates (P, d) (see :mod:`surrogate.lines`): a tensor grid of rows P in the normal
plane times a 1-D grid of positions d along Δ.  Because the model is ``T = Σ_i L_i(P) f_i(d)``, its values on the
grid are the small matrix product ``L (rows × l) · Fᵀ (l × n_d)``; the l Lagrange functions are evaluated once per
row and the l line models once per d.  The hull of the sampled segments is convex, so in every row it is one
interval of d, found from the hull's half-spaces; only those points exist in the grid.  A numba kernel walks the
rows in parallel, skips the points the (optional) feasibility mask rejects and keeps each row's minimum.

Grid spacing is isotropic in the caller's units (the map (P, d) → X is a rotation plus the scaling ‖Δ‖ of d), chosen
so the region holds about ``n_points`` points.  The best grid point is polished on the model: SLSQP in a box of
±1.5 grid steps with the hull's half-spaces as linear constraints, accepted only if the feasibility predicate
accepts it; otherwise (or if SLSQP fails) a seeded random local search that rejects infeasible points.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from numba import njit, prange
from scipy.optimize import minimize
from scipy.spatial import ConvexHull, QhullError

from mechopt.surrogate.errors import SurrogateError
from mechopt.surrogate.lines import FeasiblePredicate
from mechopt.surrogate.model import SparseExponentialModel


@dataclass(eq=False)
class SearchResult:
    """Outcome of :func:`exhaustive_search` (in the spirit of :class:`scipy.optimize.OptimizeResult`).

    Attributes
    ----------
    x : (d,) array
        Best point found (caller's units); NaN when nothing feasible was found.
    fun : float
        Model value at ``x`` (data units).
    success : bool
        Whether a feasible grid point was found.
    message : str
        What happened, in one line.
    n_evaluated : int
        Model evaluations performed (grid plus polish).
    n_feasible : int
        Grid points accepted by the feasibility predicate (all grid points when it is None).
    n_grid : int
        Grid points inside the search region (hull, or its bounding box when ``hull=False``).
    timings : dict
        Wall-clock seconds of the stages: ``grid``, ``feasibility``, ``evaluation``, ``polish``, ``total``.
    x_grid : (d,) array
        Best grid point before polishing.
    fun_grid : float
        Model value there.
    spacing : float
        Grid step (caller's units).
    polish : str
        How the polish ended: ``"slsqp"``, ``"local-sampling"`` or ``"none"``.
    """

    x: np.ndarray
    fun: float
    success: bool
    message: str
    n_evaluated: int
    n_feasible: int
    n_grid: int
    timings: dict[str, float] = field(default_factory=dict)
    x_grid: np.ndarray | None = None
    fun_grid: float = np.nan
    spacing: float = np.nan
    polish: str = "none"

    def __repr__(self) -> str:
        items = {k: getattr(self, k) for k in self.__dataclass_fields__}
        width = max(len(k) for k in items)
        return "\n".join(f"{k.rjust(width)}: {v!r}" for k, v in items.items())


@dataclass(eq=False)
class HullGrid:
    """Grid of the search region in plan coordinates, stored row by row.

    Attributes
    ----------
    rows : (n_rows, m) array
        Normal-plane coordinates P of the rows (caller's units); empty rows are dropped.
    d : (n_d,) array
        Positions along Δ (sample steps).
    lo : (n_rows,) int array
        Index into ``d`` of each row's first point.
    counts : (n_rows,) int array
        Number of points of each row (consecutive in ``d``).
    offsets : (n_rows,) int array
        Position of each row's first point in the flattened grid.
    steps : (m + 1,) array
        Grid steps in (P, d) coordinates.
    spacing : float
        Isotropic grid step in the caller's units.
    equations : (n_facets, m + 2) array
        Half-spaces ``a·(P, d) + b <= 0`` of the region in plan coordinates.
    """

    rows: np.ndarray
    d: np.ndarray
    lo: np.ndarray
    counts: np.ndarray
    offsets: np.ndarray
    steps: np.ndarray
    spacing: float
    equations: np.ndarray

    @property
    def n_points(self) -> int:
        """Total number of grid points."""
        return int(self.counts.sum())

    def coordinates(self, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
        """Plan coordinates (P (k, m), d (k,)) of flattened grid points ``start .. stop − 1``."""
        flat = np.arange(start, stop, dtype=np.int64)
        row = np.searchsorted(self.offsets, flat, side="right") - 1
        return self.rows[row], self.d[self.lo[row] + flat - self.offsets[row]]


@njit(parallel=True, cache=True)
def _row_minima(L, F, lo, counts, offsets, mask, use_mask):  # pragma: no cover - compiled
    n_rows, n_lines = L.shape
    best = np.empty(n_rows)
    arg = np.empty(n_rows, dtype=np.int64)
    n_eval = np.zeros(n_rows, dtype=np.int64)
    for a in prange(n_rows):
        bv = np.inf
        bj = -1
        ne = 0
        off = offsets[a]
        base = lo[a]
        for t in range(counts[a]):
            if use_mask and not mask[off + t]:
                continue
            b = base + t
            s = 0.0
            for i in range(n_lines):
                s += L[a, i] * F[b, i]
            ne += 1
            if s < bv:
                bv = s
                bj = b
        best[a] = bv
        arg[a] = bj
        n_eval[a] = ne
    return best, arg, n_eval


def _plan_hull_equations(model: SparseExponentialModel) -> tuple[np.ndarray, np.ndarray, float]:
    """Hull of the sampled segments in plan coordinates: (points, equations, volume in caller's units^d)."""
    plan = model.plan
    ends = plan.segment_ends()
    P, d = plan.coordinates(ends)
    pts = np.column_stack([P, d])
    try:
        hull = ConvexHull(pts)
    except QhullError as exc:
        raise SurrogateError(
            f"the hull of the {plan.n_lines} sampled segments is flat in {plan.dim}-D; it cannot be searched"
        ) from exc
    return pts, hull.equations, float(hull.volume) * plan.spacing


def hull_grid(model: SparseExponentialModel, n_points: int = 10_000_000, hull: bool = True) -> HullGrid:
    """Build the search grid of a fitted model.

    Parameters
    ----------
    model : SparseExponentialModel
        Fitted model (its plan's ``k_ranges`` define the hull).
    n_points : int
        Approximate number of grid points in the region.
    hull : bool
        Restrict the grid to the hull of the sampled segments (True) or use the hull's bounding box in plan
        coordinates (False; the model then extrapolates between the hull and the box).

    Returns
    -------
    HullGrid
    """
    model._require_fit()
    if int(n_points) < 8:
        raise SurrogateError(f"n_points must be at least 8, got {n_points}")
    plan = model.plan
    pts, eqs, volume = _plan_hull_equations(model)
    lo_b, hi_b = pts.min(axis=0), pts.max(axis=0)
    dim = plan.dim
    scale_axes = np.ones(dim)
    scale_axes[-1] = plan.spacing  # one unit of d is ‖Δ‖ long
    if not hull:
        volume = float(np.prod((hi_b - lo_b) * scale_axes))
    h = (volume / int(n_points)) ** (1.0 / dim)
    axes = []
    for v in range(dim):
        extent = (hi_b[v] - lo_b[v]) * scale_axes[v]
        n_v = max(2, int(round(extent / h)) + 1)
        axes.append(np.linspace(lo_b[v], hi_b[v], n_v))
    steps = np.array([(a[-1] - a[0]) / (a.size - 1) for a in axes])
    rows = np.stack(np.meshgrid(*axes[:-1], indexing="ij"), axis=-1).reshape(-1, dim - 1)
    dgrid = axes[-1]
    n_d = dgrid.size
    if hull:
        a_p, a_d, b = eqs[:, :-2], eqs[:, -2], eqs[:, -1]
        tol = 1e-9 * float(np.max(np.ptp(pts, axis=0)))
        rhs = -(rows @ a_p.T) - b[None, :] + tol  # a_d * d <= rhs
        with np.errstate(divide="ignore", invalid="ignore"):
            bound = rhs / a_d[None, :]
        up = np.where(a_d > 0, bound, np.inf).min(axis=1)
        low = np.where(a_d < 0, bound, -np.inf).max(axis=1)
        flat_ok = np.all(np.where(a_d == 0, rhs >= 0, True), axis=1)
        lo_idx = np.ceil((low - dgrid[0]) / steps[-1] - 1e-9)
        hi_idx = np.floor((up - dgrid[0]) / steps[-1] + 1e-9)
        lo_idx = np.clip(lo_idx, 0, n_d).astype(np.int64)
        hi_idx = np.clip(hi_idx, -1, n_d - 1).astype(np.int64)
        counts = np.where(flat_ok, np.maximum(hi_idx - lo_idx + 1, 0), 0)
    else:
        lo_idx = np.zeros(rows.shape[0], dtype=np.int64)
        counts = np.full(rows.shape[0], n_d, dtype=np.int64)
        box = np.column_stack([np.eye(dim), -hi_b])
        eqs = np.vstack([box, np.column_stack([-np.eye(dim), lo_b])])
    keep = counts > 0
    rows, lo_idx, counts = rows[keep], lo_idx[keep], counts[keep].astype(np.int64)
    offsets = np.concatenate(([0], np.cumsum(counts)[:-1])).astype(np.int64)
    return HullGrid(rows, dgrid, lo_idx, counts, offsets, steps, float(h), eqs)


def grid_minimum(
    model: SparseExponentialModel, grid: HullGrid, mask: np.ndarray | None = None
) -> tuple[float, np.ndarray, np.ndarray, int]:
    """Smallest model value over the (masked) grid points.

    Parameters
    ----------
    model : SparseExponentialModel
        Fitted model.
    grid : HullGrid
        Grid from :func:`hull_grid`.
    mask : (grid.n_points,) bool array, optional
        Points to consider (e.g. the feasible ones); all when None.

    Returns
    -------
    fun : float
        Minimum value (inf if no point is considered).
    P : (m,) array
        Normal-plane coordinates of the minimiser.
    d : float array of shape ()
        Its position along Δ.
    n_evaluated : int
        Number of model evaluations done.
    """
    L = np.ascontiguousarray(model.blend.lagrange(grid.rows))
    F = np.ascontiguousarray(model.line_values(grid.d))
    use_mask = mask is not None
    if use_mask:
        mask = np.ascontiguousarray(mask, dtype=np.bool_)
        if mask.size != grid.n_points:
            raise SurrogateError(f"mask must have {grid.n_points} entries, got {mask.size}")
    else:
        mask = np.ones(1, dtype=np.bool_)
    best, arg, n_eval = _row_minima(L, F, grid.lo, grid.counts, grid.offsets, mask, use_mask)
    n_total = int(n_eval.sum())
    if best.size == 0 or not np.isfinite(best).any():
        return np.inf, np.full(grid.rows.shape[1], np.nan), np.array(np.nan), n_total
    a = int(np.nanargmin(best))
    return float(best[a]), grid.rows[a].copy(), np.array(grid.d[arg[a]]), n_total


def _feasibility_mask(
    model: SparseExponentialModel, grid: HullGrid, feasible: FeasiblePredicate, chunk: int
) -> np.ndarray:
    mask = np.empty(grid.n_points, dtype=bool)
    for start in range(0, grid.n_points, chunk):
        stop = min(start + chunk, grid.n_points)
        P, d = grid.coordinates(start, stop)
        ok = np.asarray(feasible(model.plan.from_coordinates(P, d)), dtype=bool).reshape(-1)
        if ok.size != stop - start:
            raise SurrogateError(f"feasible() must return {stop - start} booleans, got {ok.size}")
        mask[start:stop] = ok
    return mask


class _Polisher:
    """Local minimisation of the model around a grid point in scaled plan coordinates."""

    def __init__(self, model: SparseExponentialModel, grid: HullGrid, feasible: FeasiblePredicate | None):
        self.model = model
        self.grid = grid
        self.feasible = feasible
        self.n_eval = 0
        self.tol = 1e-9 * float(np.max(grid.steps))

    def value(self, z: np.ndarray) -> np.ndarray:
        z = np.atleast_2d(z)
        self.n_eval += z.shape[0]
        return self.model.predict_coordinates(z[:, :-1], z[:, -1])

    def admissible(self, z: np.ndarray) -> np.ndarray:
        z = np.atleast_2d(z)
        eq = self.grid.equations
        ok = np.all(z @ eq[:, :-1].T + eq[:, -1] <= self.tol, axis=1)
        if self.feasible is not None and ok.any():
            X = self.model.plan.from_coordinates(z[ok, :-1], z[ok, -1])
            ok[ok] = np.asarray(self.feasible(X), dtype=bool).reshape(-1)
        return ok

    def slsqp(self, z0: np.ndarray, f0: float) -> tuple[np.ndarray, float] | None:
        h = self.grid.steps
        eq = self.grid.equations
        A, b = eq[:, :-1] * h, eq[:, :-1] @ z0 + eq[:, -1]

        def fun(y):
            return float(self.value(z0 + h * y)[0])

        def jac(y):
            z = z0 + h * y
            return self.model.gradient_coordinates(z[None, :-1], z[None, -1])[0] * h

        cons = {"type": "ineq", "fun": lambda y: -(A @ y + b), "jac": lambda y: -A}
        res = minimize(
            fun,
            np.zeros(z0.size),
            jac=jac,
            method="SLSQP",
            bounds=[(-1.5, 1.5)] * z0.size,
            constraints=[cons],
            options={"ftol": 1e-14, "maxiter": 200},
        )
        z = z0 + h * res.x
        if not np.all(np.isfinite(z)):
            return None
        f = float(self.value(z)[0])
        if f <= f0 and self.admissible(z)[0]:
            return z, f
        return None

    def local_sampling(
        self, z0: np.ndarray, f0: float, batch: int = 128, max_rounds: int = 400, seed: int = 0
    ) -> tuple[np.ndarray, float]:
        """Random local search with rejection of infeasible points (extreme barrier).

        Each round samples ``batch`` points in a ball of radius r grid steps around the best point; the best point
        moves on improvement (r grows by 1.5), otherwise r halves.  Random directions, unlike a coordinate
        stencil, keep finding the thin cone of improving moves along a curved constraint surface, so the search
        slides along it to the constrained minimum.
        """
        rng = np.random.default_rng(seed)
        h = self.grid.steps
        z_best, f_best = z0, f0
        r = 1.0
        dim = z0.size
        for _ in range(max_rounds):
            u = rng.standard_normal((batch, dim))
            u *= (rng.random(batch) ** (1.0 / dim) / np.linalg.norm(u, axis=1))[:, None]
            Z = z_best + r * u * h
            ok = self.admissible(Z)
            improved = False
            if ok.any():
                cand = Z[ok]
                vals = self.value(cand)
                j = int(np.argmin(vals))
                if vals[j] < f_best:
                    z_best, f_best, improved = cand[j], float(vals[j]), True
            r = min(1.5 * r, 2.0) if improved else 0.5 * r
            if r < 1e-5:
                break
        return z_best, f_best


def _polished(model: SparseExponentialModel, grid: HullGrid, feasible: FeasiblePredicate | None, z0: np.ndarray,
              f0: float, polish: bool) -> tuple[np.ndarray, float, str, int]:
    """The grid minimum ``z0`` (plan coordinates) refined on the model, if ``polish``: SLSQP, else local sampling.

    Returns the point, its model value (data units), how it was polished and the model evaluations it took.
    """
    if not polish:
        return z0, f0, "none", 0
    polisher = _Polisher(model, grid, feasible)
    res = polisher.slsqp(z0, f0)
    if res is not None:
        z, f = res
        return z, f, "slsqp", polisher.n_eval
    z, f = polisher.local_sampling(z0, f0)
    return z, f, "local-sampling", polisher.n_eval


def exhaustive_search(
    model: SparseExponentialModel,
    feasible: FeasiblePredicate | None = None,
    n_points: int = 10_000_000,
    hull: bool = True,
    polish: bool = True,
    chunk: int = 1_000_000,
) -> SearchResult:
    """Global minimum of the model on a dense grid of the hull ∩ feasible region, polished locally.

    Parameters
    ----------
    model : SparseExponentialModel
        Fitted model.
    feasible : callable, optional
        ``feasible(X: (n, d) array) -> (n,) bool array`` (caller's units); may cost ~1 µs per point, so it is
        called on chunks of ``chunk`` grid points.  None accepts every point.
    n_points : int
        Approximate number of grid points in the region.
    hull : bool
        Search only the hull of the sampled segments (where the model is valid); False searches the hull's
        bounding box in plan coordinates.
    polish : bool
        Refine the best grid point on the model (SLSQP within the hull, else a random local search), keeping it
        feasible.
    chunk : int
        Number of grid points per call of ``feasible``.

    Returns
    -------
    SearchResult
    """
    model._require_fit()
    if int(chunk) < 1:
        raise SurrogateError(f"chunk must be a positive integer, got {chunk}")
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    grid = hull_grid(model, n_points, hull)
    timings["grid"] = time.perf_counter() - t_start

    t = time.perf_counter()
    mask = None if feasible is None else _feasibility_mask(model, grid, feasible, int(chunk))
    timings["feasibility"] = time.perf_counter() - t
    n_feasible = grid.n_points if mask is None else int(mask.sum())

    t = time.perf_counter()
    fun, P, d, n_eval = grid_minimum(model, grid, mask)
    timings["evaluation"] = time.perf_counter() - t

    if not np.isfinite(fun):
        timings["polish"] = 0.0
        timings["total"] = time.perf_counter() - t_start
        nan = np.full(model.plan.dim, np.nan)
        message = f"no feasible point among {grid.n_points} grid points"
        return SearchResult(nan, np.nan, False, message, n_eval, n_feasible, grid.n_points, timings, nan, np.nan,
                            grid.spacing, "none")

    x_grid = model.plan.from_coordinates(P[None, :], np.atleast_1d(d))[0]
    t = time.perf_counter()
    z, f, how, n_polish = _polished(model, grid, feasible, np.concatenate([P, np.atleast_1d(d)]), fun, polish)
    timings["polish"] = time.perf_counter() - t
    x = model.plan.from_coordinates(z[None, :-1], z[-1:])[0]
    timings["total"] = time.perf_counter() - t_start
    message = (
        f"minimum over {n_feasible} feasible of {grid.n_points} grid points (step {grid.spacing:.3g}); polish: {how}"
    )
    return SearchResult(x, f, True, message, n_eval + n_polish, n_feasible, grid.n_points, timings, x_grid, fun,
                        grid.spacing, how)
