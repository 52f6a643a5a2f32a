"""The plan of a study run, before its first simulation: each stage, its simulations, and the expected wall time.

A user of an expensive simulator (a CAD motion study of 85 s, paper 002) commits hours with ``--budget``; the plan
says what the run will cost before it starts (``mechopt study ... --dry-run`` prints it and simulates nothing), and
every run prints it first.  It counts the designs the sample store already holds (a resumed run costs less), and
prices the others from the simulator's declared cost (``[simulator] seconds_per_run``) or, better, from the median
wall time the store recorded for this problem's earlier simulations.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mechopt.optimize.methods import get_method
from mechopt.optimize.sparse.model import ObjectiveModel
from mechopt.optimize.sparse.options import SparseOptions
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.optimize.sparse.stage import planned_designs
from mechopt.runs.store import SampleStore, design_key
from mechopt.studies.catalogue import Study
from mechopt.studies.method_time import method_seconds, method_time_line

__all__ = ["PlanStage", "RunPlan", "duration_text", "open_store_if_any", "plan_run",
           "plan_validation", "seconds_per_run"]



@dataclass(frozen=True)
class PlanStage:
    """One stage of the plan.

    Attributes
    ----------
    name : str
        What the stage does.
    simulations : int
        Most designs it asks for.
    held : int
        Of those, how many the store already holds (not simulated again).
    parallel : bool
        Whether its designs run ``workers`` at a time (lines, held-out lines, and every step of the
        sparse methods, proposed in batches of ``workers``) or one after the other (the baselines).
    exact : bool
        Whether ``simulations`` is the count (True) or an upper bound (the refinement may stop earlier).
    width : int, optional
        Most designs a round of this stage holds whatever the workers (the local search: a design and its
        gradient's d, d + 1); None: the workers.
    """

    name: str
    simulations: int
    held: int = 0
    parallel: bool = True
    exact: bool = True
    width: int | None = None

    @property
    def new(self) -> int:
        """Designs this stage will simulate."""
        return max(0, self.simulations - self.held)

    def rounds(self, workers: int) -> int:
        """Rounds of simulations run at the same time: ``new / workers`` rounded up, or ``new`` one after the
        other."""
        at_once = max(1, workers if self.width is None else min(workers, self.width))
        return math.ceil(self.new / at_once) if self.parallel else self.new

    def seconds(self, per_run: float, workers: int) -> float:
        """Expected wall time (s) at ``per_run`` seconds a simulation on ``workers`` workers: rounds × per_run."""
        return self.rounds(workers) * per_run


@dataclass(frozen=True)
class RunPlan:
    """Every stage of a run, the budget and what one simulation costs.

    Attributes
    ----------
    stages : list of PlanStage
        In the order they run.
    budget : int
        Most simulations to optimise.
    validation : int
        Held-out simulations on top of the budget (0: none).
    workers : int
        Simulations run at the same time.
    per_run : float or None
        Seconds a simulation (None: unknown).
    cost_source : str
        Where ``per_run`` comes from.
    headline : str, optional
        The plan's first line, when it is not a budget to optimise (``mechopt validate``); the workers follow it.
    """

    stages: list[PlanStage]
    budget: int
    validation: int
    workers: int
    per_run: float | None
    cost_source: str
    headline: str | None = None
    #: The method's own computing (s; None: not measured for it), from :mod:`mechopt.studies.method_time`.
    method_s: float | None = None
    #: The problem's discrete variables and how many designs they allow (empty when all are continuous).
    space: str = ""

    @property
    def total(self) -> int:
        """Most designs the run asks for."""
        return sum(s.simulations for s in self.stages)

    @property
    def new(self) -> int:
        """Most designs the run simulates (the store holds the others)."""
        return sum(s.new for s in self.stages)

    @property
    def rounds(self) -> int:
        """Rounds of at most ``workers`` simulations at once that the run expects (one simulation's time each)."""
        return sum(s.rounds(self.workers) for s in self.stages)

    @property
    def seconds(self) -> float | None:
        """Expected wall time of the simulations (s; None when the cost of one is unknown): rounds × per_run."""
        if self.per_run is None:
            return None
        return sum(s.seconds(self.per_run, self.workers) for s in self.stages)

    def text(self) -> list[str]:
        """The plan as printed before the run."""
        head = self.headline
        if head is None:
            share = (f"{self.validation} held-out simulations on top of it ({self.validation / self.budget:.0%})"
                     if self.validation else "no held-out validation")
            head = f"plan: budget {self.budget} simulations to optimise, {share}"
        lines = [f"{head}; {self.workers} at a time"] + ([f"  {self.space}"] if self.space else [])
        for s in self.stages:
            count = f"{s.simulations}" if s.exact else f"up to {s.simulations}"
            held = f", {s.held} already in the store" if s.held else ""
            when = "" if self.per_run is None else f", about {duration_text(s.seconds(self.per_run, self.workers))}"
            width = self.workers if s.width is None else min(self.workers, s.width)
            order = (" (one at a time)" if not s.parallel else
                     f" ({s.rounds(self.workers)} round{'' if s.rounds(self.workers) == 1 else 's'} of "
                     f"{width})" if self.workers > 1 else "")
            lines.append(f"  {s.name}: {count} simulation{'' if s.simulations == 1 else 's'}{held}{order}{when}")
        cost = "unknown" if self.seconds is None else (
            f"about {duration_text(self.seconds)} on {self.workers} worker{'' if self.workers == 1 else 's'} "
            f"({self.rounds} rounds × {self.per_run:.3g} s)")
        lines.append(f"  in all: at most {self.total} designs, {self.new} to simulate; expected simulation time {cost} "
                     f"({self.cost_source})")
        lines.append(method_time_line(self.method_s, self.seconds))
        return lines

    def to_dict(self) -> dict:
        """JSON-able plan (``result.json`` → ``plan``)."""
        return {"budget": self.budget, "validation": self.validation, "workers": self.workers,
                "seconds_per_run": self.per_run, "cost_source": self.cost_source, "total": self.total,
                "new": self.new, "expected_s": self.seconds, "rounds": self.rounds, "method_s": self.method_s,
                "space": self.space,
                "stages": [{"name": s.name, "simulations": s.simulations, "held": s.held, "parallel": s.parallel,
                            "exact": s.exact, "rounds": s.rounds(self.workers)} for s in self.stages]}


def duration_text(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def seconds_per_run(study: Study, store: SampleStore | None) -> tuple[float | None, str]:
    """Seconds one simulation costs, and where that figure comes from.

    The median of the wall times the store recorded for this problem (a measurement beats a declaration), else
    ``[simulator] seconds_per_run``, else None.
    """
    from mechopt.studies.kinds.simulator_section import declared_seconds_per_run

    declared = declared_seconds_per_run(study.file) if study.file is not None else None
    times = []
    if store is not None:
        times = [r.wall_time_s for r in store.records(study.problem.fingerprint()) if r.wall_time_s is not None]
    if times:
        also = f"; declared {declared:g} s" if declared is not None else ""
        return float(statistics.median(times)), (f"{statistics.median(times):.3g} s a simulation: the median of "
                                                  f"{len(times)} recorded in the store{also}")
    if declared is not None:
        return declared, f"{declared:g} s a simulation, declared in [simulator] seconds_per_run"
    return None, ("the time of one simulation is unknown: declare [simulator] seconds_per_run, or run once and the "
                  "store's recorded times are used")


def _held(store: SampleStore | None, designs: np.ndarray, fingerprint: str, retry_failed: bool) -> int:
    """How many of the designs the store holds a result for (a failed one is simulated again on --retry-failed)."""
    if store is None or not len(designs):
        return 0
    records = store.get_many([tuple(map(float, d)) for d in designs], fingerprint)
    keys = {design_key(tuple(map(float, d))) for d in designs}
    return sum(1 for k in keys if k in records and not (retry_failed and records[k].status == "failed"))


def plan_run(study: Study, options: SparseOptions, method: str, store: SampleStore | None, workers: int,
             retry_failed: bool = False) -> RunPlan:
    """The plan of a study run: no simulation, only the line plan's geometry and look-ups in the store.

    Parameters
    ----------
    study : Study
        The study (its problem and reference designs).
    options : SparseOptions
        The budget, the line plan and the validation.
    method : str
        The optimizer (only a line model has lines to count and held-out lines to validate).
    store : SampleStore, optional
        The store the run will use (None: a new one).
    workers : int
        Simulations run at the same time.
    retry_failed : bool
        Whether failed designs in the store will be simulated again.
    """
    problem = study.problem
    fingerprint = problem.fingerprint()
    budget = int(options.budget)
    stages: list[PlanStage] = []
    record = get_method(method)
    if record.line_model:
        stages.append(_line_stage(study, options, store, retry_failed))
        n_lines = stages[-1].simulations
        stages.append(PlanStage("confirm the model's candidate", 1))
        if options.refine and budget - n_lines - 1 > 0:
            stages.extend(_refinement(budget - n_lines - 1, workers, problem.dim))
        n_val_lines, per_line = options.validation_plan()
    else:
        # mechopt's other methods propose batches of ``workers`` designs; the baselines one at a time.
        stages.append(PlanStage(f"method {method}", budget, parallel=record.batches, exact=False))
        n_val_lines, per_line = 0, 0
    validation = n_val_lines * per_line
    if validation:
        stages.append(PlanStage(f"validate: {n_val_lines} held-out lines of {per_line}", validation, exact=False))
    references = study.reference_designs()
    if references:
        stages.append(PlanStage(f"reference designs ({', '.join(references)})", len(references),
                                _held(store, np.vstack(list(references.values())), fingerprint, retry_failed)))
    per_run, source = seconds_per_run(study, store)
    return RunPlan(stages, budget, validation, workers, per_run, source,
                   method_s=method_seconds(method, problem.dim, budget), space=problem.space_text(budget))


def _line_stage(study: Study, options: SparseOptions, store: SampleStore | None, retry_failed: bool) -> PlanStage:
    """The lines of the global model: their distinct designs, and how many of them the store holds."""
    plan, _, designs = planned_designs(ModelSpace(study.problem), options, options.n_lines, options.samples_per_line,
                                       options.plan == "paper", options.line_cap())
    on_lines = np.vstack(designs)
    n = len({design_key(tuple(map(float, d))) for d in on_lines})
    return PlanStage(f"global model: {plan.n_lines} lines", n,
                     _held(store, on_lines, study.problem.fingerprint(), retry_failed))


def plan_validation(study: Study, options: SparseOptions, store: SampleStore | None, workers: int,
                    model: ObjectiveModel | None = None, retry_failed: bool = False) -> RunPlan:
    """The plan of ``mechopt validate``: the line model's lines when there is no saved ``model``, then the held-out
    lines.  With a saved model they are placed here as the run will place them (seeded, no simulation), and the store
    is asked which it holds; a model still to be fitted places them later, so ``validation_lines`` of
    ``validation_points`` is then an upper bound."""
    from mechopt.optimize.sparse.validate import validation_lines

    lines, points = options.validation_lines, options.validation_points
    if model is None:
        stages = [_line_stage(study, options, store, retry_failed),
                  PlanStage(f"validate: {lines} held-out lines of {points}", lines * points, exact=False)]
        headline = f"plan: a line model of {stages[0].simulations} simulations, then up to {lines * points} held-out"
    else:
        placed = validation_lines(model, ModelSpace(study.problem), lines, points, options.seed)
        designs = np.vstack(placed) if placed else np.zeros((0, study.problem.dim))
        n = len({design_key(tuple(map(float, d))) for d in designs})
        stages = [PlanStage(f"validate the saved line model: {len(placed)} held-out lines of {points}", n,
                            _held(store, designs, study.problem.fingerprint(), retry_failed))]
        headline = f"plan: the saved line model, {n} held-out simulations"
    per_run, source = seconds_per_run(study, store)
    return RunPlan(stages, 0, stages[-1].simulations, workers, per_run, source, headline=headline)


def _refinement(left: int, workers: int, dim: int) -> list[PlanStage]:
    """The sparse method's refinement: one stage one at a time; with batches, the model steps in rounds of
    ``workers`` (whole rounds of their share of what is left, as the pipeline takes them) and the local search's
    designs with their gradients, d + 1 a round."""
    from mechopt.optimize.sparse.pipeline import model_step_budget

    if workers <= 1:
        return [PlanStage("refine on the simulator (model steps, SLSQP, corrected steps)", left, exact=False)]
    steps = model_step_budget(left, workers)
    stages = [PlanStage("refine: model steps", steps, exact=False)]
    if left > steps:
        stages.append(PlanStage("refine: local search (each design with its gradient) and corrected steps",
                                left - steps, exact=False, width=dim + 1))
    return stages


def open_store_if_any(path: Path) -> SampleStore | None:
    """The store at ``path`` when it exists (a dry run creates no file), else None."""
    return SampleStore(path) if Path(path).is_file() else None
