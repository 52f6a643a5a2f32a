"""The study workflow: plan lines, sample, fit, search, refine, confirm (paper Algorithm 1 and Section 4).

1. **Global model**: l parallel lines planned automatically over the feasible region (or the paper's Δ and origin),
   sampled through the resumable store, fitted with sums of exponentials and blended (Eq. 17); its exhaustive search
   gives a first candidate, which is simulated to confirm it.
2. **Refinement**: the candidate is refined by a constrained local search (SLSQP with counted finite differences)
   on the simulator itself, within what is left of the simulation budget.  For the ventilator a single quadratic
   blend across the lines' normal plane is only a few per cent accurate (its best least-squares quadratic already
   misses by ~3 %), enough to find the basin of the optimum but not its last per cent.
3. The best *simulated* candidate is the optimum; nothing is reported from the model alone.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from mechopt.sim.fourbar.feasibility import check_feasibility, constraint_margins
from mechopt.surrogate import LinePlan, SparseExponentialModel, exhaustive_search, plan_lines
from mechopt.surrogate.planner import LAYOUTS

from .design_space import DesignSpace, from_u, to_u
from .evaluate import Evaluator
from .sampling import sample_designs
from .store import SampleStore


@dataclass
class SurrogateOptions:
    """Settings of the surrogate pipeline (study TOML section ``[surrogate]``; CLI flags override).

    Attributes
    ----------
    plan : str
        ``"auto"`` (planner) or ``"paper"`` (the study's ``paper_direction`` and ``paper_origin``, U coordinates).
    target : str
        What the lines' exponential sums model: ``"mean_square"`` (T_RMS², the mean of τ² over the cycle, whose
        square root is taken after blending) or ``"rms"`` (T_RMS itself, as the paper).  T_RMS² is the smoother
        function of the design: on the ventilator the blend's held-out error is halved.
    layout : str
        How the planner places the line nodes: ``"fekete"`` (approximate Fekete points, an accurate blend for any
        l) or ``"boundary"`` (on the region's outline, the largest hull for l = 7); see :mod:`surrogate.planner`.
    n_lines, samples_per_line, min_samples : int
        Lines of the global model, target samples per line, fewest samples a line may have.
    max_order : int
        Largest number of exponential terms per line.
    search_points : int
        Grid points of the global exhaustive search (the paper: 10 million).
    refine : bool
        Refine the model's candidate by a constrained local search on the simulator.
    fd_step : float
        Finite-difference step of that search, as a fraction of the region's width: large enough to step over
        the simulator's numerical noise (pymunk: ~1e-4 relative, smooth), small enough for accurate gradients.
    budget : int
        Most simulations in all: the model's lines, the confirmation and the refinement (the paper used 618).
    rel_tol : float
        Simulation and model agree when they differ by less than this, relatively.
    validation_lines, validation_points : int
        Held-out lines and most points per line.
    toggle_relax_deg, box_extend : float
        How far beyond the toggle margin and the box lines may be sampled (see :mod:`studies.design_space`).
    paper_direction, paper_origin : list of float
        The paper's Δ and origin over (|OA|, |BC|, |AB|), for ``plan = "paper"``.
    seed : int
        Seed of the planner and of the validation lines.
    """

    plan: str = "auto"
    target: str = "mean_square"
    layout: str = "fekete"
    n_lines: int = 21
    samples_per_line: int = 25
    min_samples: int = 20
    max_order: int = 5
    search_points: int = 10_000_000
    refine: bool = True
    fd_step: float = 1e-3
    budget: int = 600
    rel_tol: float = 0.005
    validation_lines: int = 10
    validation_points: int = 30
    toggle_relax_deg: float = 5.0
    box_extend: float = 0.15
    paper_direction: list[float] = field(default_factory=lambda: [0.0, 0.920, 0.503])
    paper_origin: list[float] = field(default_factory=lambda: [31.000, 257.859, 72.705])
    seed: int = 0

    @classmethod
    def from_study(cls, section: dict, overrides: dict | None = None) -> SurrogateOptions:
        """Options from a study's ``[surrogate]`` section and CLI overrides; unknown keys are errors."""
        from mechopt.errors import StudyError

        known = {f for f in cls.__dataclass_fields__}
        values = {}
        for key, value in {**section, **{k: v for k, v in (overrides or {}).items() if v is not None}}.items():
            if key not in known:
                raise StudyError(f"unknown key surrogate.{key}; expected one of {sorted(known)}")
            default = getattr(cls(), key)
            if isinstance(default, bool) or not isinstance(value, type(default) if not isinstance(default, float)
                                                           else (int, float)):
                if not (isinstance(default, list) and isinstance(value, list)):
                    raise StudyError(f"key surrogate.{key} = {value!r} must be of type {type(default).__name__}")
            values[key] = value
        opts = cls(**values)
        if opts.plan not in ("auto", "paper"):
            raise StudyError(f"key surrogate.plan = {opts.plan!r}; expected 'auto' or 'paper'")
        if opts.layout not in LAYOUTS:
            raise StudyError(f"key surrogate.layout = {opts.layout!r}; expected one of {', '.join(LAYOUTS)}")
        if opts.target not in TARGETS:
            raise StudyError(f"key surrogate.target = {opts.target!r}; expected one of {', '.join(TARGETS)}")
        for key in ("n_lines", "samples_per_line", "min_samples", "max_order", "search_points", "budget"):
            if getattr(opts, key) < 1:
                raise StudyError(f"key surrogate.{key} = {getattr(opts, key)!r} must be >= 1")
        return opts


TARGETS = ("mean_square", "rms")


class ObjectiveModel:
    """The sparse model of T_RMS or of T_RMS², answering in T_RMS (N·m) either way.

    Everything but :meth:`predict` (plan, orders, hull, terms...) is the underlying
    :class:`~surrogate.SparseExponentialModel`'s.
    """

    def __init__(self, model: SparseExponentialModel, target: str = "mean_square"):
        if target not in TARGETS:
            raise ValueError(f"target must be one of {TARGETS}, got {target!r}")
        self.model = model
        self.target = target

    def __getattr__(self, name: str):
        if name == "model":  # not set yet (e.g. while unpickling): no recursion
            raise AttributeError(name)
        return getattr(self.model, name)

    def predict(self, U: np.ndarray) -> np.ndarray:
        """T_RMS (N·m) at paper coordinates U (n, 3)."""
        value = np.asarray(self.model.predict(U), dtype=float)
        return np.sqrt(np.maximum(value, 0.0)) if self.target == "mean_square" else value

    def save(self, path: Path) -> None:
        """JSON file with the target and the model."""
        Path(path).write_text(json.dumps({"target": self.target, "model": self.model.to_dict()}))

    @classmethod
    def load(cls, path: Path) -> ObjectiveModel:
        """Inverse of :meth:`save`."""
        data = json.loads(Path(path).read_text())
        return cls(SparseExponentialModel.from_dict(data["model"]), data["target"])


class Sampler:
    """Simulate designs through the resumable store, counting what each stage cost."""

    def __init__(self, evaluator: Evaluator, store: SampleStore, executor=None, progress: bool = True):
        self.evaluator = evaluator
        self.store = store
        self.executor = executor
        self.progress = progress
        self.key = evaluator.settings_hash()
        self.designs: set[tuple[float, float, float]] = set()
        self.n_computed = 0
        self.n_cached = 0
        self.sampling_time_s = 0.0

    def __call__(self, designs: np.ndarray, desc: str) -> tuple[np.ndarray, np.ndarray]:
        """T_RMS and T_max (N·m) of designs (n, 3) in mm; NaN where the simulation did not succeed."""
        designs = np.atleast_2d(designs)
        t0 = time.perf_counter()
        res = sample_designs([tuple(map(float, d)) for d in designs], self.evaluator, self.store, self.key,
                             executor=self.executor, progress=self.progress, desc=desc)
        self.sampling_time_s += time.perf_counter() - t0
        self.n_computed += res.n_computed
        self.n_cached += res.n_cached
        self.designs.update(tuple(map(float, d)) for d in designs)
        t_rms = np.array([r.t_rms if r.ok else np.nan for r in res.records], dtype=float)
        t_max = np.array([r.t_max if r.ok else np.nan for r in res.records], dtype=float)
        return t_rms, t_max


@dataclass
class Stage:
    """One model of the pipeline: its box, plan, samples, fit, search and confirmation."""

    name: str
    box: np.ndarray
    plan: LinePlan
    coverage: float
    model: ObjectiveModel
    line_designs: list[np.ndarray]
    line_values: list[np.ndarray]
    candidate: np.ndarray
    predicted: float
    simulated: float
    simulated_max: float
    search_time_s: float
    fit_time_s: float
    n_samples: int

    @property
    def agreement(self) -> float:
        """Relative difference between simulation and model at the candidate."""
        return abs(self.simulated - self.predicted) / self.simulated

    def summary(self) -> dict:
        """JSON-able summary."""
        return {
            "name": self.name, "box_mm": self.box.tolist(), "coverage": self.coverage,
            "n_lines": self.plan.n_lines, "n_samples": self.n_samples, "orders": self.model.orders,
            "direction_u": self.plan.direction.tolist(), "candidate_mm": self.candidate.tolist(),
            "predicted_t_rms_Nm": self.predicted, "simulated_t_rms_Nm": self.simulated,
            "relative_disagreement": self.agreement, "fit_time_s": self.fit_time_s,
            "search_time_s": self.search_time_s,
        }


#: Lines of the paper's plan (its Section 4: l = 7, quadratic blend plus one cubic term).
PAPER_LINES = 7


def _paper_plan(space: DesignSpace, options: SurrogateOptions) -> LinePlan:
    """The paper's Δ, spacing ‖Δ‖, origin (U coordinates) and l = 7, with offsets from the planner in that
    direction."""
    direction = np.asarray(options.paper_direction, dtype=float)
    res = plan_lines(to_u(space.box[:, 0]), to_u(space.box[:, 1]), space.feasible_u, n_lines=PAPER_LINES,
                     spacing=float(np.linalg.norm(direction)), samples_per_line=options.samples_per_line,
                     min_samples=min(options.min_samples, options.samples_per_line), n_random=0, n_refine=0,
                     seed=options.seed, sampleable=space.sampleable_u, directions=[direction])
    plan = res.plan
    # Express the same lines from the paper's origin: shift every offset by the difference of origins.
    shift = plan.origin - np.asarray(options.paper_origin, dtype=float)
    return LinePlan(plan.direction, np.asarray(options.paper_origin, dtype=float), plan.offsets + shift,
                    k_ranges=plan.k_ranges), res.coverage


def build_stage(name: str, space: DesignSpace, options: SurrogateOptions, sampler: Sampler, n_lines: int,
                samples_per_line: int, search_points: int, paper: bool = False,
                min_samples: int | None = None, max_order: int | None = None,
                max_samples: int | None = None) -> Stage:
    """Plan, sample, fit and search one model over ``space``, then simulate its candidate (``max_samples`` caps the
    lines' samples, so that a budget is never exceeded)."""
    lo_u, hi_u = to_u(space.box[:, 0]), to_u(space.box[:, 1])
    min_samples = min(options.min_samples if min_samples is None else min_samples, samples_per_line)
    if paper:
        plan, cov = _paper_plan(space, options)
    else:
        res = plan_lines(lo_u, hi_u, space.feasible_u, n_lines=n_lines, samples_per_line=samples_per_line,
                         min_samples=min_samples, seed=options.seed, sampleable=space.sampleable_u,
                         layout=options.layout)
        plan, cov = res.plan, res.coverage
    if max_samples is not None:
        plan = _trim(plan, max_samples)
    line_designs, line_values, samples, k_ranges = [], [], [], []
    all_designs = [from_u(plan.points(i, np.arange(k0, k1 + 1))) for i, (k0, k1) in enumerate(plan.k_ranges)]
    values, _ = sampler(np.vstack(all_designs), desc=f"{name}: {plan.n_lines} lines")
    start = 0
    for i, designs in enumerate(all_designs):
        v = values[start : start + len(designs)]
        start += len(designs)
        ks = np.arange(plan.k_ranges[i][0], plan.k_ranges[i][1] + 1)
        run = _longest_finite_run(v)  # a failed simulation splits a line: fit its longest clean stretch
        ks, v, designs = ks[run], v[run], designs[run]
        samples.append((ks, v * v if options.target == "mean_square" else v))
        k_ranges.append([int(ks[0]), int(ks[-1])])
        line_designs.append(designs)
        line_values.append(v)
    plan = plan.with_k_ranges(np.array(k_ranges))
    t0 = time.perf_counter()
    model = ObjectiveModel(
        SparseExponentialModel(max_order=options.max_order if max_order is None else max_order).fit(plan, samples),
        options.target,
    )
    fit_time = time.perf_counter() - t0
    t0 = time.perf_counter()
    # Minimising T_RMS² is minimising T_RMS: the search runs on the underlying model.
    found = exhaustive_search(model.model, feasible=space.feasible_u_fast, n_points=search_points)
    search_time = time.perf_counter() - t0
    candidate = _make_feasible(space, from_u(found.x), line_designs)
    predicted = float(model.predict(to_u(candidate)[None, :])[0])
    sim_rms, sim_max = sampler(candidate[None, :], desc=f"{name}: confirm")
    return Stage(name=name, box=space.box.copy(), plan=plan, coverage=float(cov), model=model,
                 line_designs=line_designs, line_values=line_values, candidate=candidate, predicted=predicted,
                 simulated=float(sim_rms[0]), simulated_max=float(sim_max[0]), search_time_s=search_time,
                 fit_time_s=fit_time, n_samples=int(sum(len(v) for v in line_values)))


def _trim(plan: LinePlan, max_samples: int) -> LinePlan:
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


def _longest_finite_run(values: np.ndarray) -> np.ndarray:
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


def _make_feasible(space: DesignSpace, design: np.ndarray, line_designs: list[np.ndarray]) -> np.ndarray:
    """The search's design if it passes the full feasibility check, else pulled towards the nearest sample."""
    if space.feasible(design)[0]:
        return design
    pool = np.vstack(line_designs)
    pool = pool[space.feasible(pool)]
    anchor = pool[np.argmin(np.linalg.norm(pool - design, axis=1))]
    lo, hi = 0.0, 1.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if space.feasible(design + mid * (anchor - design))[0]:
            hi = mid
        else:
            lo = mid
    return design + hi * (anchor - design)


@dataclass
class PipelineResult:
    """Outcome of :func:`optimize`: every stage, the best simulated design and the accounting."""

    stages: list[Stage]
    best: Stage
    n_fit_simulations: int
    sampling_time_s: float
    message: str

    @property
    def x(self) -> np.ndarray:
        """Optimal design (mm)."""
        return self.best.candidate

    @property
    def fun(self) -> float:
        """Its simulated T_RMS (N·m)."""
        return self.best.simulated


def optimize(space: DesignSpace, options: SurrogateOptions, sampler: Sampler, log=print) -> PipelineResult:
    """The global model and its candidate, then a constrained local refinement on the simulator if needed."""
    used_before = len(sampler.designs)
    # The lines may use the budget but one simulation, which confirms the candidate.
    stage = build_stage("global", space, options, sampler, options.n_lines, options.samples_per_line,
                        options.search_points, paper=options.plan == "paper", max_samples=options.budget - 1)
    log(f"  global model: {stage.n_samples} samples on {stage.plan.n_lines} lines (coverage {stage.coverage:.0%}), "
        f"orders {stage.model.orders}; candidate {np.round(stage.candidate, 3).tolist()} mm, model "
        f"{stage.predicted:.4f}, simulated {stage.simulated:.4f} N·m")
    stages = [stage]
    best = stage
    message = f"model and simulation agree within {stage.agreement:.2%} at the candidate"
    remaining = options.budget - (len(sampler.designs) - used_before)
    # Agreement at one point does not prove the candidate optimal (the model may be off elsewhere), so the local
    # search always runs when there is budget: at a true optimum it stops after a few gradient evaluations.
    # One forward-difference gradient costs d simulations beyond the start: below that a local search cannot move.
    if options.refine and remaining > space.box.shape[0] + 1:
        refined = refine_locally(space, sampler, stage.candidate, remaining, stage, options.fd_step)
        stages.append(refined)
        log(f"  refinement: {refined.n_samples} simulations of a constrained local search (SLSQP) from the "
            f"candidate; design {np.round(refined.candidate, 3).tolist()} mm, simulated {refined.simulated:.4f} N·m")
        if refined.simulated < best.simulated:
            best = refined
        message = (f"model and simulation differ by {stage.agreement:.2%} at the model's candidate; a local search on "
                   f"the simulator moved it from {stage.simulated:.4f} to {best.simulated:.4f} N·m")
    elif stage.agreement > options.rel_tol:
        message = f"model and simulation disagree by {stage.agreement:.2%} at the candidate; no budget left to refine"
    return PipelineResult(stages=stages, best=best, n_fit_simulations=len(sampler.designs) - used_before,
                          sampling_time_s=sampler.sampling_time_s, message=message)


def refine_locally(space: DesignSpace, sampler: Sampler, x0: np.ndarray, budget: int, model_stage: Stage,
                   fd_step: float = 1e-3) -> Stage:
    """SLSQP on the simulator itself from ``x0``, with the feasibility margins as constraints (budgeted).

    Where the global model is off by more than the tolerance, its candidate is only a good start: the objective
    near it is smooth, the optimum typically sits on a constraint, and a gradient method with counted forward
    differences reaches it in a few dozen simulations.
    """
    from .baselines.problem import BudgetExhausted, CountedProblem
    from .baselines.slsqp import local_slsqp

    def objective(x: np.ndarray) -> float:
        value, _ = sampler(np.asarray(x, dtype=float)[None, :], desc="refinement")
        return float(value[0])

    def margins(x: np.ndarray) -> np.ndarray:
        return constraint_margins(x, space.mechanism)

    progress, sampler.progress = sampler.progress, False
    t0 = time.perf_counter()
    problem = CountedProblem(objective, space.box, budget, margins)
    try:
        local_slsqp(problem, x0, fd_step=fd_step)
    except BudgetExhausted:
        pass
    finally:
        sampler.progress = progress
    x = problem.best_x if problem.best_x is not None else x0
    sim_rms, sim_max = sampler(np.asarray(x)[None, :], desc="refinement")
    return Stage(name="local refinement", box=space.box.copy(), plan=model_stage.plan, coverage=model_stage.coverage,
                 model=model_stage.model, line_designs=[], line_values=[], candidate=np.asarray(x, dtype=float),
                 predicted=float(model_stage.model.predict(to_u(np.asarray(x))[None, :])[0]),
                 simulated=float(sim_rms[0]), simulated_max=float(sim_max[0]),
                 search_time_s=time.perf_counter() - t0, fit_time_s=0.0, n_samples=problem.nfev)


@dataclass
class Validation:
    """Held-out simulations against the global model (paper Fig. 16)."""

    lines: list[dict]
    rmse: float
    rmse_low: float
    max_error: float
    t_min: float
    n_points: int

    def summary(self) -> dict:
        """JSON-able summary (lines with their points)."""
        return asdict(self)


def validation_lines(model: ObjectiveModel, space: DesignSpace, n_lines: int, n_points: int,
                     seed: int) -> list[np.ndarray]:
    """Held-out lines inside the model's hull ∩ feasible region, in directions at least 30° from Δ (designs, mm)."""
    rng = np.random.default_rng(seed + 1000)
    delta = model.plan.direction / np.linalg.norm(model.plan.direction)
    lo_u, hi_u = to_u(space.box[:, 0]), to_u(space.box[:, 1])
    cloud = rng.uniform(lo_u, hi_u, size=(40_000, 3))
    cloud = cloud[model.contains(cloud) & space.feasible_u(cloud)]
    lines = []
    tries = 0
    while len(lines) < n_lines and tries < 50 * n_lines and len(cloud):
        tries += 1
        u = rng.standard_normal(3) * (hi_u - lo_u)
        u /= np.linalg.norm(u)
        if abs(u @ delta) > np.cos(np.radians(30)):
            continue
        through = cloud[rng.integers(len(cloud))]
        extent = float(np.linalg.norm(hi_u - lo_u))
        s = np.linspace(-extent, extent, 4001)
        pts = through + s[:, None] * u
        ok = model.contains(pts) & space.feasible_u(pts)
        i0 = int(np.argmin(np.abs(s)))
        if not ok[i0]:
            continue
        a, b = i0, i0
        while a > 0 and ok[a - 1]:
            a -= 1
        while b < len(s) - 1 and ok[b + 1]:
            b += 1
        if s[b] - s[a] < 0.1 * extent:
            continue
        ts = np.linspace(s[a], s[b], n_points)
        lines.append(from_u(through + ts[:, None] * u))
    return lines


def validate(model: ObjectiveModel, space: DesignSpace, sampler: Sampler, n_lines: int, n_points: int,
             seed: int, t_min: float | None = None) -> Validation:
    """Simulate held-out lines and compare with the model: RMSE overall, for T <= 2 T_min, and max error."""
    lines = validation_lines(model, space, n_lines, n_points, seed)
    records = []
    sims, preds = [], []
    for j, designs in enumerate(lines):
        sim, _ = sampler(designs, desc=f"validation line {j + 1}/{len(lines)}")
        pred = model.predict(to_u(designs))
        ok = np.isfinite(sim)
        records.append({"designs_mm": designs[ok].tolist(), "simulated": sim[ok].tolist(),
                        "predicted": np.asarray(pred)[ok].tolist()})
        sims.append(sim[ok])
        preds.append(np.asarray(pred)[ok])
    sim = np.concatenate(sims) if sims else np.array([])
    pred = np.concatenate(preds) if preds else np.array([])
    err = pred - sim
    t_min = float(np.min(sim)) if t_min is None and sim.size else float(t_min or np.nan)
    low = sim <= 2 * t_min
    return Validation(
        lines=records,
        rmse=float(np.sqrt(np.mean(err**2))) if err.size else float("nan"),
        rmse_low=float(np.sqrt(np.mean(err[low] ** 2))) if low.any() else float("nan"),
        max_error=float(np.max(np.abs(err))) if err.size else float("nan"),
        t_min=t_min,
        n_points=int(sim.size),
    )


def feasible_report(design: np.ndarray, space: DesignSpace) -> dict:
    """Margins of a design (mm or deg)."""
    return check_feasibility(design, space.mechanism).margins(0)
