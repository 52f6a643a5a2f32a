"""Run a whole study: optimise, validate, evaluate the reference designs, report.

Everything a run produces goes to one folder: ``result.json`` (machine-readable), ``report.md`` (for people),
``figures/`` and ``model.json`` (the global model, reusable without simulating again); the sample store defaults to
``samples.sqlite`` there, so a killed run resumes where it stopped.  The brute-force ground truth is opt-in
(``truth=True``), cached by the problem's fingerprint.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.ground_truth import GroundTruth, load_or_compute
from mechopt.optimize.result import OptimizeResult
from mechopt.optimize.sparse.options import SparseOptions
from mechopt.optimize.sparse.pipeline import run_pipeline
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.optimize.sparse.trust import study_trust
from mechopt.optimize.sparse.validate import Validation, validate
from mechopt.runs.executors import make_executor
from mechopt.runs.store import SampleStore
from mechopt.studies.catalogue import Study

__all__ = ["StudyRun", "check_output_folder", "run_study", "study_options", "summary_lines"]


@dataclass
class StudyRun:
    """Everything a study run computed."""

    study: Study
    options: SparseOptions
    result: OptimizeResult
    validation: Validation | None
    references: dict[str, dict[str, Any]]
    truth: GroundTruth | None
    timings: dict[str, float]
    out: Path
    store_path: Path
    sampling: dict[str, Any] = field(default_factory=dict)
    failures: list = field(default_factory=list)


def study_options(study: Study, overrides: dict[str, Any] | None = None) -> SparseOptions:
    """The sparse options of a study: its ``[surrogate]`` section, then the command line's overrides."""
    values = {**study.section("surrogate"), **{k: v for k, v in (overrides or {}).items() if v is not None}}
    return SparseOptions(values, where="surrogate.")


def check_output_folder(out: Path) -> Path:
    """An output folder (with its ``figures`` sub-folder) that exists or can be made, and is writable.

    Raises
    ------
    InputError
        One line naming the folder: a file in its place, a read-only folder, or a folder that cannot be made.
    """
    out = Path(out)
    for folder in (out, out / "figures"):
        if folder.exists():
            if not folder.is_dir():
                raise InputError(f"--out {out}: {folder} is a file; expected a folder")
            if not os.access(folder, os.W_OK | os.X_OK):
                raise InputError(f"--out {out}: the folder {folder} is read-only")
            continue
        parent = next((p for p in folder.parents if p.exists()), None)
        if parent is not None and not os.access(parent, os.W_OK | os.X_OK):
            raise InputError(f"--out {out}: cannot create {folder}: the folder {parent} is read-only")
        try:
            folder.mkdir(parents=True)
        except OSError as exc:
            raise InputError(f"--out {out}: cannot create {folder} ({exc.strerror or exc})") from None
    return out


def run_study(study: Study, out: Path, options: SparseOptions, workers: int | None = None,
              scheduler: str | None = None, store_path: Path | None = None, progress: bool = True,
              truth: bool = False, truth_step: float = 1.0, retry_failed: bool = False,
              log: Callable[[str], None] = print) -> StudyRun:
    """Run the study end to end and write its outputs to ``out``.

    Parameters
    ----------
    study : Study
        The study (its problem carries the engine).
    out : Path
        Output folder (checked before any simulation).
    options : SparseOptions
        Pipeline settings.
    workers, scheduler : optional
        Local processes, or a Dask scheduler address.
    store_path : Path, optional
        The sample store (default ``out/samples.sqlite``).
    progress : bool
        Progress bars.
    truth : bool
        Also brute-force the ground truth (problems with a batch evaluator), cached in ``out``.
    truth_step : float
        Its grid step, in the variables' unit.
    retry_failed : bool
        Simulate again the designs whose earlier simulation failed.
    log : callable
        Where progress lines go.
    """
    from mechopt.report.study_report import write_outputs

    out = check_output_folder(out)
    store_path = Path(store_path) if store_path else out / "samples.sqlite"
    problem = study.problem
    space = ModelSpace(problem)
    timings: dict[str, float] = {}
    t_all = time.perf_counter()
    with SampleStore(store_path) as store, make_executor(workers=workers, scheduler=scheduler) as executor:
        sampler = Sampler(problem, store, executor, progress, retry_failed)
        log(f"study {study.name}: {problem!r}, store {store_path}, {sampler.executor_description}")
        t0 = time.perf_counter()
        pipeline = run_pipeline(space, options, sampler, log=log)
        timings["optimise_s"] = time.perf_counter() - t0
        n_opt = len(sampler.designs)
        log(f"  {pipeline.message}; {pipeline.n_simulations} simulations ({pipeline.stages[0].n_samples} on the "
            "lines of the global model)")
        validation = None
        if options.validation_lines > 0:
            t0 = time.perf_counter()
            validation = validate(pipeline.stages[0].model, space, sampler, options.validation_lines,
                                  options.validation_points, options.seed, f_min=pipeline.fun)
            timings["validation_s"] = time.perf_counter() - t0
            log(f"  validation: {validation.n_points} held-out simulations on {len(validation.lines)} lines, RMSE "
                f"{validation.rmse:.4g} ({validation.relative_text()}), max {validation.max_error:.4g}")
        n_val = len(sampler.designs) - n_opt
        pipeline.stages[0].model.save(out / "model.json")
        t0 = time.perf_counter()
        refs = {**study.reference_designs(), "optimum": pipeline.x}
        records = sampler.records(np.vstack(list(refs.values())), desc="reference designs")
        references = {name: {"design": study.problem.design_dict(x), "status": r.status, "outputs": dict(r.outputs),
                             "error": r.error, "feasible": bool(problem.feasible(x)[0])}
                      for (name, x), r in zip(refs.items(), records, strict=True)}
        timings["references_s"] = time.perf_counter() - t0
        sampling = {**sampler.summary(), "optimisation": n_opt, "validation": n_val,
                    "references": len(sampler.designs) - n_opt - n_val}
        failures = [(np.array(d), e) for d, e in sampler.failures.values()]
    ground = None
    truth_file = out / f"ground_truth_{truth_step:g}.json"
    if truth or truth_file.is_file():
        t0 = time.perf_counter()
        ground = load_or_compute(problem, truth_file, truth_step, compute=truth)
        timings["ground_truth_s"] = time.perf_counter() - t0
    trust = study_trust(pipeline.stages[0], pipeline.best, validation)
    log(f"  trust: {trust['verdict']}")
    result = OptimizeResult(x=pipeline.x, fun=pipeline.fun, nfev=n_opt, success=bool(np.isfinite(pipeline.fun)),
                            message=pipeline.message, method="sparse", model=pipeline.stages[0].model,
                            stages=pipeline.stages, validation=validation,
                            outputs=references["optimum"]["outputs"], trust=trust)
    timings["total_s"] = time.perf_counter() - t_all
    run = StudyRun(study, options, result, validation, references, ground, timings, out, store_path, sampling,
                   failures)
    t0 = time.perf_counter()
    write_outputs(run)
    timings["report_s"] = time.perf_counter() - t0
    return run


def summary_lines(run: StudyRun) -> list[str]:
    """The final summary printed by ``mechopt study``."""
    problem = run.study.problem
    opt = run.references["optimum"]["outputs"]
    obj = problem.objective
    lines = [f"optimum {problem.describe(run.result.x)}: {obj} {run.result.fun:.6g}"
             + "".join(f", {k} {v:.6g}" for k, v in opt.items() if k in problem.outputs and k != obj)]
    orig = run.references.get("original")
    if orig is not None and orig["status"] == "ok" and orig["outputs"].get(obj):
        lines.append(f"original: {obj} {orig['outputs'][obj]:.6g} -> savings "
                     f"{100 * (1 - run.result.fun / orig['outputs'][obj]):.1f} %")
    if run.truth is not None:
        lines.append(f"ground truth (brute force, grid {run.truth.step:g} + polish): "
                     f"{problem.describe(np.array(run.truth.x))}, {obj} {run.truth.fun:.6g}; gap "
                     f"{100 * (run.result.fun / run.truth.fun - 1):+.2f} %")
    s = run.sampling
    lines.append(f"simulations: {s['optimisation']} to optimise ({run.result.stages[0].n_samples} on the lines of the "
                 f"global model), {s['validation']} to validate, {s['references']} reference designs; "
                 f"{s['new']} new, {s['reused']} reused from the store, {s['failed']} failed, "
                 f"{s['waited_for_other_runs']} computed by another run; {s['executor']}; "
                 f"total {run.timings['total_s']:.1f} s; outputs in {run.out}")
    return lines
