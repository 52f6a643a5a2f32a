"""Run a whole study: optimise, validate, simulate the reference designs, compare with the ground truth, report.

Everything a run produces goes to one folder: ``result.json`` (machine-readable), ``report.md`` (for people),
``figures/`` and ``model.json`` (the global model, reusable without re-simulating); the sample store defaults to
``samples.sqlite`` there, so a killed run resumes where it stopped.
"""

from __future__ import annotations

import json
import time
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from mechopt.sim.fourbar.simulate import simulate

from .definition import Study
from .design_space import DesignSpace
from .evaluate import Evaluator
from .executors import make_executor
from .ground_truth import load_or_compute
from .store import SampleStore
from .workflow import PipelineResult, Sampler, SurrogateOptions, Validation, optimize, validate


@dataclass
class StudyRun:
    """Everything a study run computed."""

    study: Study
    options: SurrogateOptions
    pipeline: PipelineResult
    validation: Validation
    references: dict
    truth: object
    timings: dict
    out: Path


def make_space(study: Study, options: SurrogateOptions) -> DesignSpace:
    """The study's design space with the sampling relaxations of ``options``."""
    return DesignSpace(study.mechanism, study.region, options.toggle_relax_deg, options.box_extend)


def open_sampler(study: Study, engine: str, store_path: Path, workers: int | None, scheduler: str | None,
                 progress: bool):
    """Store, executor and sampler for a run (use the returned executor as a context manager)."""
    store = SampleStore(store_path)
    executor = make_executor(workers=workers, scheduler=scheduler)
    sampler = Sampler(Evaluator(study.mechanism, engine, study.name), store, executor, progress)
    return store, executor, sampler


def run_study(study: Study, out: Path, options: SurrogateOptions, engine: str = "pymunk", workers: int | None = None,
              scheduler: str | None = None, store_path: Path | None = None, progress: bool = True,
              truth_step_mm: float = 1.0, log=print) -> StudyRun:
    """Run the study end to end and write its outputs to ``out``.

    Parameters
    ----------
    study : Study
        The study.
    out : Path
        Output folder.
    options : SurrogateOptions
        Surrogate settings.
    engine : str
        Simulation engine of the samples (``"pymunk"`` plays the CAD; ``"analytic"`` is faster).
    workers, scheduler : optional
        Local processes, or a Dask scheduler address.
    store_path : Path, optional
        The sample store (default ``out/samples.sqlite``).
    progress : bool
        Show progress bars.
    truth_step_mm : float
        Grid of the brute-force ground truth the optimum is compared with (mm); 0 skips it.
    log : callable
        Where progress lines go.

    Returns
    -------
    StudyRun
    """
    from .report import write_outputs

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    store_path = Path(store_path) if store_path else out / "samples.sqlite"
    space = make_space(study, options)
    timings: dict[str, float] = {}
    t_all = time.perf_counter()
    store, executor, sampler = open_sampler(study, engine, store_path, workers, scheduler, progress)
    with store, executor if hasattr(executor, "__enter__") else nullcontext(executor):
        log(f"study {study.name}: optimising with the {engine} engine, store {store_path}")
        t0 = time.perf_counter()
        pipeline = optimize(space, options, sampler, log=log)
        timings["optimise_s"] = time.perf_counter() - t0
        timings["sampling_s"] = sampler.sampling_time_s
        timings["fit_s"] = sum(s.fit_time_s for s in pipeline.stages)
        timings["search_s"] = sum(s.search_time_s for s in pipeline.stages)
        log(f"  {pipeline.message}; {pipeline.n_fit_simulations} simulations in all ({pipeline.stages[0].n_samples} on "
            f"the lines of the global model)")
        t0 = time.perf_counter()
        before = sampler.sampling_time_s
        validation = validate(pipeline.stages[0].model, space, sampler, options.validation_lines,
                              options.validation_points, options.seed, t_min=pipeline.fun)
        timings["validation_s"] = time.perf_counter() - t0
        timings["validation_sampling_s"] = sampler.sampling_time_s - before
        log(f"  validation: {validation.n_points} held-out simulations on {len(validation.lines)} lines, RMSE "
            f"{validation.rmse:.4f} N·m, {validation.rmse_low:.4f} N·m where T_RMS <= 2 T_min, max "
            f"{validation.max_error:.4f} N·m")
        model_path = out / "model.json"
        pipeline.stages[0].model.save(model_path)

    t0 = time.perf_counter()
    references = {}
    for name in study.designs:
        references[name] = simulate(study.design(name), study.mechanism, engine="pymunk")
    references["optimum (mechopt)"] = simulate(pipeline.x, study.mechanism, engine="pymunk")
    timings["references_s"] = time.perf_counter() - t0
    truth = None
    if truth_step_mm and truth_step_mm > 0:
        t0 = time.perf_counter()
        truth = load_or_compute(study, out / f"ground_truth_{truth_step_mm:g}mm.json", truth_step_mm)
        timings["ground_truth_s"] = time.perf_counter() - t0
    timings["total_s"] = time.perf_counter() - t_all
    run = StudyRun(study, options, pipeline, validation, references, truth, timings, out)
    t0 = time.perf_counter()
    write_outputs(run, engine, store_path)
    timings["report_s"] = time.perf_counter() - t0
    # The report's own time is known only now: rewrite the JSON with it.
    result = json.loads((out / "result.json").read_text())
    result["timings_s"] = timings
    (out / "result.json").write_text(json.dumps(result, indent=2))
    return run


def summary_lines(run: StudyRun) -> list[str]:
    """The final summary printed by ``mechopt study``."""
    best = run.references["optimum (mechopt)"]
    orig = run.references.get("original")
    lines = [
        f"optimum |OA|={best.design[0]:.3f} |AB|={best.design[1]:.3f} |BC|={best.design[2]:.3f} mm: "
        f"T_RMS {best.t_rms:.4f} N·m, T_max {best.t_max:.4f} N·m (pymunk)",
    ]
    if orig is not None:
        lines.append(f"original: T_RMS {orig.t_rms:.4f} N·m, T_max {orig.t_max:.4f} N·m → savings "
                     f"{100 * (1 - best.t_rms / orig.t_rms):.1f} % RMS, "
                     f"{100 * (1 - best.t_max / orig.t_max):.1f} % max")
    if run.truth is not None:
        gap = best.t_rms / run.truth.fun - 1
        lines.append(f"ground truth (analytic brute force, {run.truth.step_mm:g} mm grid + polish): "
                     f"{np.round(run.truth.x, 3).tolist()} mm, T_RMS {run.truth.fun:.4f} N·m; gap {100 * gap:+.2f} %")
    lines.append(f"simulations: {run.pipeline.stages[0].n_samples} to fit the global model, "
                 f"{run.pipeline.n_fit_simulations - run.pipeline.stages[0].n_samples} to confirm and refine, "
                 f"{run.validation.n_points} to validate; "
                 f"total {run.timings['total_s']:.1f} s; outputs in {run.out}")
    return lines
