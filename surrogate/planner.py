"""Automatic choice of the sampling lines: direction Δ and offsets δ(i) that cover the feasible region.

The paper chose Δ and δ(i) by hand "to guarantee maximal coverage of the region of interest".  This module does it
with a cheap search whose objective is the *coverage*: the fraction of the feasible region (estimated with seeded
Monte-Carlo points of box ∩ feasible) lying inside the convex hull of the lines' feasible runs.

For every candidate direction (the principal axes of the feasible point cloud, the coordinate axes, a few random
directions, then small perturbations of the best one) the feasible cloud is projected on the normal plane and the
line nodes are placed in one of two layouts:

* ``"fekete"`` (default): approximate Fekete points of the blend's Chebyshev space (Sommariva & Vianello, *Computing
  approximate Fekete points by QR factorizations of Vandermonde matrices*, Comput. Math. Appl. 57, 2009), chosen
  among candidate nodes whose line has a long enough sampleable run.  Fekete points keep the Lebesgue constant of
  the blend small, so the interpolation across lines stays accurate as l grows, and they include the corners of the
  candidate set, so the hull reaches the region's corners, where constrained optima sit;
* ``"boundary"``: nodes on the boundary of the projected 2-D convex hull, shrunk towards its centroid (several
  shrink factors and phases are tried), plus one node at the centroid when l >= 4: the largest hull for l = 7, but
  an interpolation that degrades for l >= 10 (every node but one on a closed curve).

Each line keeps its longest contiguous feasible run of samples, and the plan's coverage is the fraction of probe
points in the hull of those runs.  The best plan is re-scored on an independent set of probe points, which is the
coverage reported.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from mechopt.surrogate.errors import SurrogateError
from mechopt.surrogate.lines import FeasiblePredicate, LinePlan, normal_basis

_SHRINKS = (0.9, 0.75, 0.6)
_PHASES = (0.0, 0.5)
_MIN_RUN = 4
_RANK_POINTS = 4000
#: Node layouts of :func:`plan_lines`.
LAYOUTS = ("fekete", "boundary")
#: Candidate nodes of the Fekete layout: hull vertices of the projected cloud, widened by these factors, and a
#: subset of the projected points themselves.
_WIDEN = (1.0, 1.05, 1.1)
_INTERIOR_CANDIDATES = 150


@dataclass(frozen=True, eq=False)
class PlanResult:
    """Outcome of :func:`plan_lines`.

    Attributes
    ----------
    plan : LinePlan
        The lines, with ``k_ranges`` set to each line's feasible run (every line starts at k = 0, δ(0) = 0).
    coverage : float
        Fraction of the feasible region inside the hull of the runs (Monte-Carlo estimate on fresh points).
    coverage_error : float
        One standard error of that estimate.
    n_samples : int
        Total number of samples the plan asks for, Σ_i N_i.
    message : str
        Summary of the search.
    """

    plan: LinePlan
    coverage: float
    coverage_error: float
    n_samples: int
    message: str


def coverage(plan: LinePlan, feasible_points: Any, k_ranges: Any | None = None) -> float:
    """Fraction of points inside the hull of the plan's sampled segments.

    Parameters
    ----------
    plan : LinePlan
        Lines; ``k_ranges`` (argument or the plan's own) give the sampled segments.
    feasible_points : (n, d) array
        Points representative of the feasible region (e.g. uniform Monte-Carlo points of box ∩ feasible),
        coordinates in the caller's units.
    k_ranges : (l, 2) int array, optional
        Inclusive index range per line; defaults to ``plan.k_ranges``.

    Returns
    -------
    float
        In [0, 1]; 0 when the hull is flat (fewer than d + 1 affinely independent end points).
    """
    pts = np.atleast_2d(np.asarray(feasible_points, dtype=float))
    if pts.shape[0] == 0:
        raise SurrogateError("coverage needs at least one feasible point, got none")
    if pts.shape[1] != plan.dim:
        raise SurrogateError(f"feasible points must have {plan.dim} columns, got {pts.shape[1]}")
    try:
        hull = plan.hull(k_ranges)
    except SurrogateError:
        if k_ranges is None and plan.k_ranges is None:
            raise
        return 0.0
    return float(np.mean(hull.contains(pts)))


def _probe(lower: np.ndarray, upper: np.ndarray, feasible: FeasiblePredicate, n: int, rng) -> np.ndarray:
    X = lower + (upper - lower) * rng.random((n, lower.size))
    ok = np.asarray(feasible(X), dtype=bool).reshape(-1)
    if ok.size != n:
        raise SurrogateError(f"feasible() must return {n} booleans, got {ok.size}")
    return X[ok]


def _boundary_nodes(poly: np.ndarray, n_boundary: int, shrink: float, phase: float) -> np.ndarray:
    """Points at equal arc length on the convex polygon ``poly``, pulled towards its centroid by ``shrink``."""
    centroid = poly.mean(axis=0)
    closed = np.vstack([poly, poly[:1]])
    seg = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    cum = np.concatenate(([0.0], np.cumsum(seg)))
    s = (np.arange(n_boundary) + phase) / n_boundary * cum[-1]
    idx = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, seg.size - 1)
    t = (s - cum[idx]) / np.where(seg[idx] > 0, seg[idx], 1.0)
    pts = closed[idx] + t[:, None] * (closed[idx + 1] - closed[idx])
    return centroid + shrink * (pts - centroid)


def _simplified(poly: np.ndarray, n_keep: int) -> np.ndarray:
    """Visvalingam simplification: drop the vertex spanning the smallest triangle until ``n_keep`` remain.

    Keeps the corners of the region's cross-section, which equal-arc-length nodes tend to miss.
    """
    pts = poly.copy()
    while pts.shape[0] > n_keep:
        prev, nxt = np.roll(pts, 1, axis=0), np.roll(pts, -1, axis=0)
        a, b = prev - pts, nxt - pts
        area = 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
        pts = np.delete(pts, int(np.argmin(area)), axis=0)
    return pts


def _node_sets(P: np.ndarray, n_lines: int, shrinks: tuple[float, ...] = _SHRINKS) -> list[np.ndarray]:
    """Candidate node layouts in the normal coordinates (m = 1 or 2)."""
    out = []
    if P.shape[1] == 1:
        lo, hi = np.min(P), np.max(P)
        mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        for shrink in shrinks:
            out.append((mid + shrink * half * np.linspace(-1, 1, n_lines))[:, None])
        return out
    try:
        poly = P[ConvexHull(P).vertices]  # counter-clockwise in 2-D
    except QhullError:
        return out
    centroid = poly.mean(axis=0)
    n_boundary = n_lines - 1 if n_lines >= 4 else n_lines
    layouts = [_boundary_nodes(poly, n_boundary, 1.0, phase) for phase in _PHASES]
    if poly.shape[0] >= n_boundary:
        layouts.append(_simplified(poly, n_boundary))
    for shrink in shrinks:
        for pts in layouts:
            pts = centroid + shrink * (pts - centroid)
            out.append(np.vstack([pts, centroid[None, :]]) if n_boundary < n_lines else pts)
    return out


def fekete_points(candidates: Any, n_points: int) -> np.ndarray:
    """Indices of ``n_points`` approximate Fekete points among ``candidates`` (m = 1 to 3 coordinates).

    Greedy maximisation of the Vandermonde volume of the tensor Chebyshev basis of total degree g (the smallest
    with at least ``n_points`` functions) on the candidates' bounding box: the first pivots of a QR factorisation
    with column pivoting of the transposed Vandermonde matrix.

    Parameters
    ----------
    candidates : (n, m) array
        Candidate nodes (caller's units), n >= ``n_points``.
    n_points : int
        How many to choose.

    Returns
    -------
    (n_points,) int array
        Row indices into ``candidates``.
    """
    from numpy.polynomial.chebyshev import chebvander
    from scipy.linalg import qr

    C = np.atleast_2d(np.asarray(candidates, dtype=float))
    if C.shape[0] < n_points:
        raise SurrogateError(f"need at least {n_points} candidate nodes, got {C.shape[0]}")
    m = C.shape[1]
    lo, hi = C.min(axis=0), C.max(axis=0)
    S = 2.0 * (C - lo) / np.where(hi > lo, hi - lo, 1.0) - 1.0
    g = 0
    while _dimension(g, m) < n_points:
        g += 1
    tables = [chebvander(S[:, v], g) for v in range(m)]
    # Every product of one Chebyshev polynomial per coordinate of total degree <= g.
    degrees = [idx for idx in itertools.product(range(g + 1), repeat=m) if sum(idx) <= g]
    V = np.column_stack([np.prod([tables[v][:, a] for v, a in enumerate(idx)], axis=0) for idx in degrees])
    _, _, piv = qr(V.T, mode="economic", pivoting=True)
    return piv[:n_points]


def _dimension(g: int, m: int) -> int:
    """Number of polynomials of total degree <= g in m variables."""
    return math.comb(g + m, m)


def _longest_run_lengths(ok: np.ndarray) -> np.ndarray:
    """Length of the longest run of True in every row of ``ok``."""
    n, k = ok.shape
    padded = np.zeros((n, k + 2), dtype=np.int8)
    padded[:, 1:-1] = ok
    rows, cols = np.nonzero(np.diff(padded, axis=1))
    # Edges alternate rise, fall within a row: a run's length is fall − rise.
    lengths = cols[1::2] - cols[0::2]
    out = np.zeros(n, dtype=int)
    np.maximum.at(out, rows[0::2], lengths)
    return out


def _fekete_layout(P: np.ndarray, c: np.ndarray, E: np.ndarray, delta: np.ndarray, feasible: FeasiblePredicate,
                   n_lines: int, min_samples: int, k_lo: int, k_hi: int, rng) -> np.ndarray | None:
    """Fekete nodes among candidates whose line has >= ``min_samples`` samples where ``feasible`` holds."""
    centroid = P.mean(axis=0)
    if P.shape[1] == 1:
        ends = np.array([[P.min()], [P.max()]])
    else:
        try:
            ends = P[ConvexHull(P).vertices]
        except QhullError:
            return None
    widened = [centroid + f * (ends - centroid) for f in _WIDEN]
    inner = P[rng.choice(P.shape[0], min(_INTERIOR_CANDIDATES, P.shape[0]), replace=False)]
    cand = np.vstack([*widened, inner])
    ks = np.arange(k_lo, k_hi + 1)
    pts = c + (cand @ E)[:, None, :] + ks[None, :, None] * delta
    ok = np.asarray(feasible(pts.reshape(-1, c.size)), dtype=bool).reshape(cand.shape[0], ks.size)
    cand = cand[_longest_run_lengths(ok) >= min_samples]
    if cand.shape[0] < n_lines:
        return None
    return cand[fekete_points(cand, n_lines)]


def _evaluate(
    u: np.ndarray,
    spacing: float | None,
    samples_per_line: int,
    F: np.ndarray,
    feasible: FeasiblePredicate,
    n_lines: int,
    min_samples: int,
    shrinks: tuple[float, ...] = _SHRINKS,
    layout: str = "fekete",
    rng=None,
) -> tuple[float, LinePlan | None]:
    """Best plan (and its coverage of the probe cloud F) for the unit direction u."""
    E = normal_basis(u)
    c = F.mean(axis=0)
    t = (F - c) @ u
    step = spacing if spacing is not None else (t.max() - t.min()) / max(samples_per_line - 1, 1)
    if not step > 0:
        return 0.0, None
    delta = step * u
    P = (F - c) @ E.T
    k_lo = int(np.floor(t.min() / step)) - 1
    k_hi = int(np.ceil(t.max() / step)) + 1
    best = (0.0, None)
    if layout == "fekete":
        nodes = _fekete_layout(P, c, E, delta, feasible, n_lines, min_samples, k_lo, k_hi,
                               rng if rng is not None else np.random.default_rng(0))
        layouts = [] if nodes is None else [nodes]
    else:
        layouts = _node_sets(P, n_lines, shrinks)
    for nodes in layouts:
        base = LinePlan(delta, c, nodes @ E)
        runs = [base.feasible_run(i, feasible, k_lo, k_hi) for i in range(n_lines)]
        if min(r.size for r in runs) < min_samples:
            continue
        k0 = np.array([r[0] for r in runs])
        # Re-anchor so every line starts at k = 0 and line 0 passes through the origin (paper convention).
        origin = c + nodes[0] @ E + k0[0] * delta
        offsets = (nodes - nodes[0]) @ E + (k0 - k0[0])[:, None] * delta
        k_ranges = np.array([[0, r.size - 1] for r in runs])
        plan = LinePlan(delta, origin, offsets, k_ranges=k_ranges)
        cov = coverage(plan, F)
        if cov > best[0]:
            best = (cov, plan)
    return best


def _checked_box(lower: Any, upper: Any, n_lines: int, spacing: float | None, samples_per_line: int,
                 min_samples: int, layout: str) -> tuple[np.ndarray, np.ndarray]:
    """The box bounds as float vectors, after checking every option of :func:`plan_lines` that needs no probe."""
    lo = np.asarray(lower, dtype=float).reshape(-1)
    hi = np.asarray(upper, dtype=float).reshape(-1)
    if lo.shape != hi.shape or lo.size not in (2, 3, 4):
        raise SurrogateError(f"lower and upper must be vectors of length 2 to 4, got {lo.shape} and {hi.shape}")
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi > lo)):
        raise SurrogateError(f"need finite bounds with upper > lower, got lower={lo.tolist()}, upper={hi.tolist()}")
    dim = lo.size
    if layout not in LAYOUTS:
        raise SurrogateError(f"layout must be one of {', '.join(LAYOUTS)}, got {layout!r}")
    if layout == "boundary" and dim > 3:
        raise SurrogateError(f"layout 'boundary' places nodes on a polygon (d <= 3); use 'fekete' for d = {dim}")
    if int(n_lines) < dim:
        raise SurrogateError(f"n_lines must be >= d = {dim} for the hull to have volume, got {n_lines}")
    if spacing is not None and not (np.isfinite(spacing) and spacing > 0):
        raise SurrogateError(f"spacing must be a positive length, got {spacing!r}")
    if int(samples_per_line) < _MIN_RUN:
        raise SurrogateError(f"samples_per_line must be >= {_MIN_RUN}, got {samples_per_line}")
    if not _MIN_RUN <= int(min_samples) <= int(samples_per_line):
        raise SurrogateError(
            f"min_samples must be between {_MIN_RUN} and samples_per_line = {samples_per_line}, got {min_samples}"
        )
    return lo, hi


def _ranking_probes(lo: np.ndarray, hi: np.ndarray, feasible: FeasiblePredicate, n_probe: int,
                    rng: np.random.Generator) -> np.ndarray:
    """The feasible ones of ``n_probe`` uniform points of the box; too few of them make the coverage meaningless."""
    F = _probe(lo, hi, feasible, int(n_probe), rng)
    if F.shape[0] < 10 * (lo.size + 1):
        raise SurrogateError(
            f"only {F.shape[0]} of {n_probe} probe points are feasible; enlarge n_probe or check the bounds"
        )
    return F


def _candidate_directions(F: np.ndarray, lo: np.ndarray, hi: np.ndarray, n_random: int, directions: Any | None,
                          rng: np.random.Generator) -> list[np.ndarray]:
    """Unit directions to try: the caller's, or the cloud's principal axes, the coordinate axes and random ones.

    The random directions are drawn even when the caller gives directions, so that the rest of the search sees the
    same random stream either way.
    """
    dim = lo.size
    # Work in box-normalised units so "principal axes" and "random directions" do not depend on the units.
    width = hi - lo
    Fn = (F - lo) / width
    _, _, vt = np.linalg.svd(Fn - Fn.mean(axis=0), full_matrices=False)
    cands = [v * width for v in vt] + list(np.eye(dim))
    rand = rng.standard_normal((n_random, dim))
    cands += [v * width for v in rand]
    if directions is not None:
        cands = [np.asarray(v, dtype=float).reshape(-1) for v in directions]
        if any(v.shape != (dim,) or not np.linalg.norm(v) > 0 for v in cands):
            raise SurrogateError(f"directions must be non-zero vectors of length {dim}")
    return [v / np.linalg.norm(v) for v in cands]


class _DirectionSearch:
    """The best plan over the directions tried so far, each scored by :func:`_evaluate` on the ranking probes."""

    def __init__(self, F_rank: np.ndarray, spacing: float | None, samples_per_line: int, runs_on: FeasiblePredicate,
                 n_lines: int, min_samples: int, shrinks: tuple[float, ...], layout: str, rng: np.random.Generator):
        self.F_rank = F_rank
        self.spacing = spacing
        self.samples_per_line = samples_per_line
        self.runs_on = runs_on
        self.n_lines = n_lines
        self.min_samples = min_samples
        self.shrinks = shrinks
        self.layout = layout
        self.rng = rng
        self.best_cov = 0.0
        self.best_plan: LinePlan | None = None
        self.tried = 0

    def try_direction(self, u: np.ndarray) -> None:
        """Score the unit direction u and keep its plan if it covers more than the best so far."""
        cov, plan = _evaluate(u, self.spacing, self.samples_per_line, self.F_rank, self.runs_on, self.n_lines,
                              self.min_samples, self.shrinks, self.layout, self.rng)
        self.tried += 1
        if plan is not None and cov > self.best_cov:
            self.best_cov, self.best_plan = cov, plan

    def refine(self, n_refine: int) -> None:
        """Try random perturbations of the best direction, coarse then fine (``n_refine`` in all)."""
        dim = self.F_rank.shape[1]
        for angle in (0.15, 0.05):
            for _ in range(n_refine // 2):
                u0 = self.best_plan.direction / self.best_plan.spacing
                u = u0 + angle * self.rng.standard_normal(dim)
                u /= np.linalg.norm(u)
                self.try_direction(u)


def _rescored(search: _DirectionSearch, lo: np.ndarray, hi: np.ndarray, feasible: FeasiblePredicate, n_probe: int,
              n_lines: int, rng: np.random.Generator) -> PlanResult:
    """The best plan with its coverage measured again on fresh probe points (the ranking ones favour it)."""
    best_plan = search.best_plan
    F2 = _probe(lo, hi, feasible, n_probe, rng)
    cov = coverage(best_plan, F2) if F2.shape[0] else search.best_cov
    err = float(np.sqrt(cov * (1 - cov) / max(F2.shape[0], 1)))
    n_samples = int(np.sum(best_plan.k_ranges[:, 1] - best_plan.k_ranges[:, 0] + 1))
    message = (
        f"{search.tried} directions tried; coverage {cov:.3f} ± {err:.3f} of the feasible region "
        f"with {n_lines} lines, {n_samples} samples, spacing {best_plan.spacing:.4g}"
    )
    return PlanResult(best_plan, cov, err, n_samples, message)


def plan_lines(
    lower: Any,
    upper: Any,
    feasible: FeasiblePredicate,
    n_lines: int = 7,
    spacing: float | None = None,
    samples_per_line: int = 90,
    min_samples: int = 20,
    n_probe: int = 20_000,
    n_random: int = 6,
    n_refine: int = 24,
    seed: int = 0,
    sampleable: FeasiblePredicate | None = None,
    directions: Any | None = None,
    layout: str = "fekete",
) -> PlanResult:
    """Propose Δ and δ(i) whose sampled segments cover as much of the feasible region as possible.

    Parameters
    ----------
    lower, upper : (d,) array
        Box bounds of the design coordinates (caller's units), d = 2 to 4.
    feasible : callable
        ``feasible(X: (n, d) array) -> (n,) bool array``; called on arrays of probe and line points.
    n_lines : int
        Number of lines l (>= d, so the hull has volume).
    spacing : float, optional
        ‖Δ‖, the distance between samples (caller's units).  Default: the feasible extent along Δ divided by
        ``samples_per_line − 1``.
    samples_per_line : int
        Used only when ``spacing`` is None.
    min_samples : int
        Fewest samples a line's feasible run may have (shorter lines make poor exponential fits); candidate
        layouts with a shorter line are discarded.
    n_probe : int
        Monte-Carlo points drawn in the box (twice: one set to choose, one to report the coverage).
    n_random, n_refine : int
        Number of random candidate directions and of random perturbations of the best one.
    seed : int
        Seed of the Monte-Carlo points and random directions.
    sampleable : callable, optional
        Where lines may be sampled, a superset of ``feasible`` (default: ``feasible`` itself).  The objective can
        often be simulated a little outside the region the optimum must lie in (beyond the box of interest, or a
        design rule such as a toggle margin); lines that run on there all span the feasible region's whole extent
        along Δ, so no line model has to extrapolate inside the hull, and nodes may sit on the region's boundary.
    directions : sequence of (d,) arrays, optional
        Try only these directions Δ (e.g. the paper's), without random or refined candidates.
    layout : {"fekete", "boundary"}
        How the line nodes are placed in the normal plane (see the module docstring).

    Returns
    -------
    PlanResult

    Raises
    ------
    SurrogateError
        Bad bounds, d not in {2, 3, 4}, too few lines, or a feasible region the probes (almost) never hit.
    """
    lo, hi = _checked_box(lower, upper, n_lines, spacing, samples_per_line, min_samples, layout)
    rng = np.random.default_rng(seed)
    F = _ranking_probes(lo, hi, feasible, n_probe, rng)
    cands = _candidate_directions(F, lo, hi, int(n_random), directions, rng)
    # Ranking candidates needs only a few thousand points (standard error ~0.01); the full set is for reporting.
    runs_on = feasible if sampleable is None else sampleable
    # Lines that may run past the feasible region let the boundary layout put its nodes on (or beyond) its edge.
    shrinks = _SHRINKS if sampleable is None else (1.05, 1.0, *_SHRINKS)
    search = _DirectionSearch(F[:_RANK_POINTS], spacing, samples_per_line, runs_on, int(n_lines), int(min_samples),
                              shrinks, layout, rng)
    for u in cands:
        search.try_direction(u)
    if search.best_plan is None:
        raise SurrogateError(
            f"no direction gave {n_lines} lines with >= {min_samples} feasible samples each; "
            "reduce min_samples or the spacing"
        )
    search.refine(0 if directions is not None else int(n_refine))
    return _rescored(search, lo, hi, feasible, int(n_probe), n_lines, rng)
