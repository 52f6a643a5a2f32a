"""The line stage of the global sparse strategy (:mod:`mechopt.optimize.sparse_global`): a batch evaluator behind a
hard budget in unit-cube coordinates, lines planned over a box, sampled and fitted, and the basins of their blend.

Everything runs in the unit cube of the bounds, so a radius or a width is a fraction of the box.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mechopt.errors import InputError
from mechopt.surrogate import LinePlan, SparseExponentialModel, SurrogateError, exhaustive_search, plan_lines
from mechopt.surrogate.basins import Minima, field_minima, thin
from mechopt.surrogate.errors import SurrogateWarning
from mechopt.surrogate.line_error import LineOutError, blend_spread, leave_one_line_out

__all__ = ["BASIN_GRID", "MIN_LINES", "MIN_RUN", "SEARCH_POINTS", "CountedUnitCube", "FittedLines", "as_objective",
           "blend_basins", "box_predicate", "line_stage", "longest_finite_run", "trim_plan"]

Predicate = Callable[[np.ndarray], np.ndarray]
BatchEvaluator = Callable[[np.ndarray], np.ndarray]

#: Grid points per axis of the basin search (d = 2, 3, 4).
BASIN_GRID = {2: 121, 3: 33, 4: 15}
#: Grid points of the exhaustive search of a blend (paper 002: 10 million for its single model).
SEARCH_POINTS = {2: 40_000, 3: 200_000, 4: 400_000}
#: Fewest lines of a plan, per dimension (the blend needs more nodes than its normal plane has dimensions).
MIN_LINES = {2: 3, 3: 4, 4: 5}
#: Fewest samples a line keeps (a sum of exponentials of order 1 with a constant needs 4).
MIN_RUN = 4


class CountedUnitCube:
    """The batch evaluator behind a hard budget, in unit-cube coordinates, remembering every value and its source."""

    def __init__(self, evaluate: BatchEvaluator, lower: np.ndarray, width: np.ndarray, budget: int):
        self.evaluate = evaluate
        self.lower, self.width = lower, width
        self.budget = budget
        self.Z: list[np.ndarray] = []
        self.f: list[float] = []
        self.source: list[str] = []
        self._memo: dict[bytes, float] = {}

    @property
    def nfev(self) -> int:
        return len(self.f)

    @property
    def remaining(self) -> int:
        return self.budget - self.nfev

    def x(self, Z: np.ndarray) -> np.ndarray:
        return self.lower + np.atleast_2d(Z) * self.width

    def __call__(self, Z: np.ndarray, source: str) -> np.ndarray:
        """Values at unit-cube designs Z (n, d); repeated designs are free, designs beyond the budget get NaN."""
        Z = np.atleast_2d(np.asarray(Z, dtype=float))
        out = np.full(Z.shape[0], np.nan)
        todo, keys = [], []
        for j, z in enumerate(Z):
            key = z.tobytes()
            if key in self._memo:
                out[j] = self._memo[key]
            elif key not in keys and len(todo) < self.remaining:
                todo.append(j)
                keys.append(key)
        if todo:
            values = np.asarray(self.evaluate(self.x(Z[todo])), dtype=float).reshape(-1)
            if values.size != len(todo):
                raise InputError(f"evaluate returned {values.size} values for {len(todo)} designs")
            for j, key, v in zip(todo, keys, values, strict=True):
                v = float(v) if math.isfinite(v) else math.nan
                self._memo[key] = v
                self.Z.append(Z[j].copy())
                self.f.append(v)
                self.source.append(source)
        for j, z in enumerate(Z):
            out[j] = self._memo.get(z.tobytes(), np.nan)
        return out

    def best(self, feasible: Predicate) -> tuple[np.ndarray, float, str]:
        if not self.f:
            return np.full(self.lower.size, np.nan), math.nan, ""
        f = np.array(self.f)
        ok = np.isfinite(f) & feasible(np.array(self.Z))
        if not ok.any():
            return np.full(self.lower.size, np.nan), math.nan, ""
        j = int(np.flatnonzero(ok)[np.argmin(f[ok])])
        return self.Z[j], float(f[j]), self.source[j]


@dataclass
class FittedLines:
    """A line model fitted to its samples (unit-cube coordinates)."""

    model: SparseExponentialModel
    values: list[np.ndarray]
    lolo: LineOutError | None


def trim_plan(plan: LinePlan, max_samples: int) -> LinePlan:
    """Shorten the lines about their middles, in proportion, until the plan asks for at most ``max_samples``."""
    kr = np.asarray(plan.k_ranges)
    counts = kr[:, 1] - kr[:, 0] + 1
    if counts.sum() <= max_samples:
        return plan
    keep = np.maximum(MIN_RUN, np.floor(counts * max_samples / counts.sum()).astype(int))
    while keep.sum() > max_samples and keep.max() > MIN_RUN:
        keep[np.argmax(keep)] -= 1
    start = kr[:, 0] + (counts - keep) // 2
    return plan.with_k_ranges(np.column_stack([start, start + keep - 1]))


def longest_finite_run(values: np.ndarray) -> slice:
    ok = np.concatenate(([False], np.isfinite(values), [False])).astype(np.int8)
    edges = np.flatnonzero(np.diff(ok))
    if edges.size == 0:
        return slice(0, 0)
    starts, stops = edges[0::2], edges[1::2]
    j = int(np.argmax(stops - starts))
    return slice(int(starts[j]), int(stops[j]))


def box_predicate(lo: np.ndarray, hi: np.ndarray, inner: Predicate) -> Predicate:
    def pred(Z: np.ndarray) -> np.ndarray:
        Z = np.atleast_2d(Z)
        ok = np.all((Z >= lo - 1e-12) & (Z <= hi + 1e-12), axis=1)
        if ok.any():
            ok[ok] = np.asarray(inner(Z[ok]), dtype=bool).reshape(-1)
        return ok
    return pred


def line_stage(counted: CountedUnitCube, lo: np.ndarray, hi: np.ndarray, feasible: Predicate, sampleable: Predicate,
                n_lines: int, samples_per_line: int, max_samples: int, fit: str, max_order: int, seed: int,
                source: str) -> FittedLines | None:
    """Plan lines over [lo, hi] ∩ feasible, sample them (capped), fit and blend; None if no plan or fit exists."""
    min_samples = min(samples_per_line, max(MIN_RUN, samples_per_line // 2))
    res = None
    for attempt in range(3):  # a plan may fail for an odd seed or a thin region: two more seeds, nothing spent yet
        try:
            res = plan_lines(lo, hi, feasible, n_lines=n_lines, samples_per_line=samples_per_line,
                             min_samples=min_samples, n_probe=4000, n_random=4, n_refine=8, seed=seed + 1000 * attempt,
                             sampleable=sampleable, layout="fekete")
            break
        except SurrogateError:
            continue
    if res is None:
        return None
    plan = trim_plan(res.plan, max_samples)
    designs = [plan.points(i, np.arange(k0, k1 + 1)) for i, (k0, k1) in enumerate(plan.k_ranges)]
    values = counted(np.vstack(designs), source)
    samples, kept, k_ranges, start = [], [], [], 0
    for i, D in enumerate(designs):
        v = values[start : start + len(D)]
        start += len(D)
        run = longest_finite_run(v)  # a failed evaluation splits a line: fit its longest clean stretch
        ks = np.arange(plan.k_ranges[i][0], plan.k_ranges[i][1] + 1)[run]
        v = v[run]
        if v.size < 4:
            return None
        if fit == "square" and np.any(v < 0):
            raise InputError(f"fit='square' needs a non-negative objective, got {v.min():.4g} on a line")
        samples.append((ks, v * v if fit == "square" else v))
        kept.append(v * v if fit == "square" else v)
        k_ranges.append([int(ks[0]), int(ks[-1])])
    plan = plan.with_k_ranges(np.array(k_ranges))
    order_cap = max(1, min(max_order, (min(len(v) for v in kept) - 1) // 2))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SurrogateWarning)
            model = SparseExponentialModel(max_order=order_cap).fit(plan, samples)
    except SurrogateError:
        return None
    try:
        lolo = leave_one_line_out(model, kept) if model.l >= 3 else None
    except SurrogateError:
        lolo = None
    return FittedLines(model, kept, lolo)


def blend_basins(fitted: FittedLines, lo: np.ndarray, hi: np.ndarray, feasible: Predicate, kappa: float, n_model: int,
            n_bound: int, radius: float) -> tuple[Minima, Minima]:
    """Distinct minima of the blend and of ``blend − κ·spread`` over the grid of [lo, hi] ∩ hull ∩ feasible."""
    model = fitted.model
    hull = model.hull

    def region(Z: np.ndarray) -> np.ndarray:
        ok = hull.contains(Z)
        if ok.any():
            ok[ok] = np.asarray(feasible(Z[ok]), dtype=bool).reshape(-1)
        return ok

    n = BASIN_GRID[lo.size]
    by_model = field_minima(lambda Z: model.predict(Z), lo, hi, region, n, radius, n_model)
    # The paper's own answer, the exhaustive search of the blend (finer grid, polished), leads the model's minima.
    found = exhaustive_search(model, feasible=lambda Z: feasible(Z) & box_predicate(lo, hi, feasible)(Z),
                              n_points=SEARCH_POINTS[lo.size])
    if found.success:
        by_model = thin(np.vstack([found.x[None, :], by_model.x]), np.concatenate([[found.fun], by_model.value]),
                        radius, n_model)
    if kappa > 0 and n_bound > 0 and model.l >= 4:
        try:
            by_bound = field_minima(lambda Z: model.predict(Z) - kappa * blend_spread(model, Z), lo, hi, region, n,
                                    radius, n_bound)
        except SurrogateError:
            by_bound = Minima(np.zeros((0, lo.size)), np.zeros(0))
    else:
        by_bound = Minima(np.zeros((0, lo.size)), np.zeros(0))
    return by_model, by_bound


def as_objective(fit: str, value: np.ndarray) -> np.ndarray:
    value = np.asarray(value, dtype=float)
    return np.sqrt(np.maximum(value, 0.0)) if fit == "square" else value
