"""One model of the pipeline: plan lines, sample them, fit and blend, search exhaustively, confirm the candidate."""

from __future__ import annotations

import time
import weakref
from dataclasses import dataclass

import numpy as np

from mechopt.errors import MechoptError
from mechopt.optimize.sparse.allowed_candidate import best_allowed_near
from mechopt.optimize.sparse.feasible_point import pull_into_feasible
from mechopt.optimize.sparse.model import ObjectiveModel
from mechopt.optimize.sparse.options import SparseOptions
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.surrogate import LinePlan, SparseExponentialModel, exhaustive_search, plan_lines
from mechopt.surrogate.errors import SurrogateError

__all__ = ["Stage", "build_stage", "planned_designs"]


@dataclass
class Stage:
    """One model and its candidate, or a refinement of a candidate on the simulator.

    Attributes
    ----------
    name : str
        ``"global"``, ``"local refinement"``...
    plan : LinePlan
        The lines, in model coordinates.
    coverage : float
        Share of the feasible region inside the lines' hull.
    model : ObjectiveModel
        The fitted model.
    line_designs, line_values : list of ndarray
        Each line's designs (k, d) and simulated objective.
    candidate : (d,) ndarray
        The stage's design.
    predicted, simulated : float
        Model and simulation at the candidate (objective units).
    n_samples : int
        Simulations this stage asked for.
    """

    name: str
    plan: LinePlan
    coverage: float
    model: ObjectiveModel
    line_designs: list[np.ndarray]
    line_values: list[np.ndarray]
    candidate: np.ndarray
    predicted: float
    simulated: float
    search_time_s: float
    fit_time_s: float
    n_samples: int

    @property
    def agreement(self) -> float:
        """Relative difference between simulation and model at the candidate."""
        return abs(self.simulated - self.predicted) / max(abs(self.simulated), 1e-300)

    @property
    def sampled_range(self) -> float:
        """Range (max − min) of the lines' simulated values (objective units; NaN without line samples)."""
        values = np.concatenate([np.ravel(v) for v in self.line_values]) if self.line_values else np.array([])
        values = values[np.isfinite(values)]
        return float(np.ptp(values)) if values.size else float("nan")

    @property
    def claim_error(self) -> float:
        """|simulation − model| at the candidate as a fraction of :attr:`sampled_range`: unlike :attr:`agreement`,
        meaningful for an objective whose best value is near 0."""
        spread = self.sampled_range
        return abs(self.simulated - self.predicted) / spread if spread > 0 else float("nan")

    def summary(self) -> dict:
        """JSON-able summary."""
        return {
            "name": self.name, "coverage": self.coverage, "n_lines": self.plan.n_lines, "n_samples": self.n_samples,
            "orders": [int(o) for o in np.ravel(self.model.orders)], "direction_u": self.plan.direction.tolist(),
            "candidate": self.candidate.tolist(), "predicted": self.predicted, "simulated": self.simulated,
            "relative_disagreement": self.agreement, "claim_error_of_range": _or_none(self.claim_error),
            "sampled_range": _or_none(self.sampled_range), "fit_time_s": self.fit_time_s,
            "search_time_s": self.search_time_s,
        }


def _or_none(value: float) -> float | None:
    # None, not NaN, for what could not be measured: result.json stays valid JSON.
    return float(value) if np.isfinite(value) else None


def paper_plan(space: ModelSpace, options: SparseOptions) -> tuple[LinePlan, float]:
    """The paper's Δ, spacing ‖Δ‖ and origin (model coordinates) with ``paper_lines`` lines; offsets from the
    planner in that direction."""
    if options.paper_direction is None or options.paper_origin is None:
        raise MechoptError("plan = 'paper' needs surrogate.paper_direction and surrogate.paper_origin in the study")
    direction = np.asarray(options.paper_direction, dtype=float)
    origin = np.asarray(options.paper_origin, dtype=float)
    if direction.shape != (space.dim,) or origin.shape != (space.dim,):
        raise MechoptError(f"surrogate.paper_direction and paper_origin must have {space.dim} values each")
    res = plan_lines(space.lower_u, space.upper_u, space.feasible_u, n_lines=options.paper_lines,
                     spacing=float(np.linalg.norm(direction)), samples_per_line=options.samples_per_line,
                     min_samples=min(options.min_samples, options.samples_per_line), n_random=0, n_refine=0,
                     seed=options.seed, sampleable=space.sampleable_u, directions=[direction])
    plan = res.plan
    # The same lines expressed from the paper's origin: every offset shifts by the difference of origins.
    shift = plan.origin - origin
    return LinePlan(plan.direction, origin, plan.offsets + shift, k_ranges=plan.k_ranges), res.coverage


def plan_stage(space: ModelSpace, options: SparseOptions, n_lines: int, samples_per_line: int,
               paper: bool = False) -> tuple[LinePlan, float]:
    """The lines of a model over the whole region (model coordinates) and their hull's coverage."""
    if paper:
        return paper_plan(space, options)
    min_samples = min(options.min_samples, samples_per_line)
    # A small plan (3 lines of 4) asks every line to be feasible end to end; where the region's corners are thin
    # no line through them is, so a line may grow a little longer before the plan is declared impossible.
    for extra in (0, 1, 2, 4):
        try:
            res = plan_lines(space.lower_u, space.upper_u, space.feasible_u, n_lines=n_lines,
                             samples_per_line=samples_per_line + extra, min_samples=min_samples, seed=options.seed,
                             sampleable=space.sampleable_u, layout=options.layout)
            return res.plan, float(res.coverage)
        except SurrogateError as exc:
            if "no direction gave" not in str(exc) or samples_per_line > 8:
                raise
            error = exc
    raise error


#: Line plans computed in this process, by problem object (checked by a weak reference, so that a new problem at a
#: recycled id is not served another's plan) and arguments: the plan printed before a run is the plan the run then
#: samples, and finding it costs seconds of feasibility checks (3.4 s for the ventilator), so it is found once.
_PLANS: dict[tuple, tuple[weakref.ref, tuple[LinePlan, float, list[np.ndarray]]]] = {}
_PLANS_HELD = 16


def planned_designs(space: ModelSpace, options: SparseOptions, n_lines: int, samples_per_line: int,
                    paper: bool = False, max_samples: int | None = None) -> tuple[LinePlan, float, list[np.ndarray]]:
    """The lines of a model, their hull's coverage and every line's designs (k, d), before any simulation.

    What :func:`build_stage` simulates, exactly: the plan before a run counts these (and finds them in the store).
    """
    # The fingerprint and the bounds too: a mutable problem changed in place between two calls gets a new plan.
    key = (id(space.problem), space.problem.fingerprint(), np.asarray(space.box, dtype=float).tobytes(),
           repr(sorted(options.to_dict().items())), n_lines, samples_per_line, paper, max_samples)
    held = _PLANS.get(key)
    if held is not None and held[0]() is space.problem:
        plan, cov, designs = held[1]
        return plan, cov, list(designs)
    plan, cov = plan_stage(space, options, n_lines, samples_per_line, paper)
    if max_samples is not None:
        plan = trim_plan(plan, max_samples)
    all_u = [plan.points(i, np.arange(k0, k1 + 1)) for i, (k0, k1) in enumerate(plan.k_ranges)]
    designs = [space.from_u(u) for u in all_u]
    if len(_PLANS) >= _PLANS_HELD:
        _PLANS.clear()
    _PLANS[key] = (weakref.ref(space.problem), (plan, cov, designs))
    return plan, cov, list(designs)


def build_stage(name: str, space: ModelSpace, options: SparseOptions, sampler: Sampler, n_lines: int,
                samples_per_line: int, search_points: int, paper: bool = False,
                max_samples: int | None = None, max_order: int | None = None) -> Stage:
    """Plan, sample, fit and search one model, then simulate its candidate.

    ``max_samples`` caps the lines' samples so that a budget is never exceeded.
    """
    plan, cov, all_designs = planned_designs(space, options, n_lines, samples_per_line, paper, max_samples)
    fit = options.fit or space.problem.fit
    values = sampler(np.vstack(all_designs), desc=f"{name}: {plan.n_lines} lines")
    line_designs, line_values, samples, k_ranges, kept = [], [], [], [], []
    start = 0
    for i, designs in enumerate(all_designs):
        v = values[start : start + len(designs)]
        start += len(designs)
        ks = np.arange(plan.k_ranges[i][0], plan.k_ranges[i][1] + 1)
        run = longest_finite_run(v)  # a failed simulation splits a line: fit its longest clean stretch
        if run.size < 2:
            continue  # a line through a region where the simulator fails: the blend goes on without it
        ks, v, designs = ks[run], v[run], designs[run]
        samples.append((ks, v * v if fit == "square" else v))
        k_ranges.append([int(ks[0]), int(ks[-1])])
        line_designs.append(designs)
        line_values.append(v)
        kept.append(i)
    dropped = plan.n_lines - len(kept)
    if len(kept) < 2:
        raise MechoptError(f"only {len(kept)} of the {plan.n_lines} lines of the {name} model have 2 successful "
                           "simulations in a row; see the failures in the store")
    plan = LinePlan(plan.direction, plan.origin, plan.offsets[kept], k_ranges=np.array(k_ranges))
    t0 = time.perf_counter()
    sparse = SparseExponentialModel(max_order=options.max_order if max_order is None else max_order)
    try:
        model = ObjectiveModel(sparse.fit(plan, samples), fit, space.order, space.problem.names)
        fit_time = time.perf_counter() - t0
        t0 = time.perf_counter()
        # Minimising the square of a non-negative objective is minimising the objective: search the underlying
        # model.
        found = exhaustive_search(model.model, feasible=space.screen_u, n_points=search_points)
        search_time = time.perf_counter() - t0
    except SurrogateError as exc:
        if not dropped:
            raise
        raise MechoptError(f"{dropped} of the {plan.n_lines + dropped} lines of the {name} model failed to simulate "
                           f"and the others cannot make a model ({exc}); see the failures in the store, or give "
                           "more lines (--lines-fit, options={'n_lines': N})") from None
    candidate = pull_into_feasible(space, space.from_u(found.x), np.vstack(line_designs))
    candidate = best_allowed_near(space.problem, model.predict, candidate)
    predicted = float(model.predict(candidate)[0])
    simulated = float(sampler(candidate[None, :], desc=f"{name}: confirm")[0])
    return Stage(name=name, plan=plan, coverage=float(cov), model=model, line_designs=line_designs,
                 line_values=line_values, candidate=candidate, predicted=predicted, simulated=simulated,
                 search_time_s=search_time, fit_time_s=fit_time, n_samples=int(sum(len(v) for v in line_values)))


def trim_plan(plan: LinePlan, max_samples: int) -> LinePlan:
    """Shorten every line about its middle by the same factor until the plan asks for at most ``max_samples``."""
    kr = np.asarray(plan.k_ranges)
    counts = kr[:, 1] - kr[:, 0] + 1
    if counts.sum() <= max_samples:
        return plan
    keep = np.maximum(2, np.floor(counts * max_samples / counts.sum()).astype(int))
    while keep.sum() > max_samples and keep.max() > 2:
        keep[np.argmax(keep)] -= 1
    start = kr[:, 0] + (counts - keep) // 2
    return plan.with_k_ranges(np.column_stack([start, start + keep - 1]))


def longest_finite_run(values: np.ndarray) -> np.ndarray:
    """Indices of the longest run of finite values."""
    ok = np.isfinite(values)
    best, cur, best_start, start = 0, 0, 0, 0
    for i, good in enumerate(ok):
        if good:
            if cur == 0:
                start = i
            cur += 1
            if cur > best:
                best, best_start = cur, start
        else:
            cur = 0
    return np.arange(best_start, best_start + best)
