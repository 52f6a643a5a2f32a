"""Run a whole study: optimise, validate, evaluate the reference designs, report.

Everything a run produces goes to one folder: ``result.json`` (machine-readable), ``report.md`` (for people),
``figures/`` and ``model.json`` (the global model, reusable without simulating again); the sample store defaults to
``samples.sqlite`` there, so a killed run resumes where it stopped.  The brute-force ground truth is opt-in
(``truth=True``), cached by the problem's fingerprint.
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError, MechoptError
from mechopt.optimize.analysis.robust_result import make_study_robust
from mechopt.optimize.arguments import check_method
from mechopt.optimize.ground_truth import GroundTruth, load_or_compute
from mechopt.optimize.minimize import checked_options, parallel_accounting, run_method
from mechopt.optimize.result import OptimizeResult
from mechopt.optimize.sparse.model_confidence import study_trust
from mechopt.optimize.sparse.options import SparseOptions
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.optimize.sparse.validate import Validation, validate
from mechopt.report.allowed_designs_section import allowed_designs_summary
from mechopt.runs.early_stop import DEFAULT_STOP_AFTER_FAILURES
from mechopt.runs.executors import check_reachable, default_workers, make_executor
from mechopt.runs.run_journal import RunJournal, describe_run
from mechopt.runs.run_watch import watch_run
from mechopt.runs.store import SampleStore
from mechopt.runs.store_path import check_store_folder
from mechopt.studies import method_cache
from mechopt.studies.catalogue import Study
from mechopt.studies.output_folder import check_output_owner
from mechopt.studies.plan import RunPlan, duration_text, open_store_if_any, plan_run, plan_validation
from mechopt.studies.reference_check import reference_warning
from mechopt.studies.run_header import study_header
from mechopt.studies.run_options import study_options

__all__ = ["StudyRun", "check_output_folder", "check_run", "plan_study", "rounds_text", "run_study",
           "study_options", "summary_lines"]


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
    plan: RunPlan | None = None


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
              log: Callable[[str], None] = print, method: str = "sparse", x0: np.ndarray | None = None,
              stop_after_failures: int = DEFAULT_STOP_AFTER_FAILURES, force: bool = False) -> StudyRun:
    """Run the study end to end and write its outputs to ``out``.

    Parameters
    ----------
    study : Study
        The study (its problem carries the engine).
    out : Path
        Output folder (checked before any simulation).
    options : SparseOptions
        The budget, the seed and the sparse method's settings (held-out lines, too).
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
    method : str
        ``"sparse"`` (default), ``"sparse-global"`` or a baseline's name (:func:`mechopt.optimize.arguments.
        available_methods`); held-out validation needs the line model of ``"sparse"``.
    x0 : (m, d) ndarray, optional
        Checked designs simulated first; they count in ``options.budget``, as in :func:`mechopt.minimize`.
    stop_after_failures : int
        Stop when the run's first this-many simulations all failed (0: never), as in :func:`mechopt.minimize`.
    force : bool
        Use ``out`` even when it holds another study's or another problem's results (they are removed first).
    """
    from mechopt.report.study_report import write_outputs

    problem = study.problem
    out, store_path = _checked_places(study, out, options, method, scheduler, store_path, force)
    timings: dict[str, float] = {}
    t_all = time.perf_counter()
    with SampleStore(store_path) as store, make_executor(workers=workers, scheduler=scheduler) as executor, \
            contextlib.ExitStack() as watching:
        sampler = Sampler(problem, store, executor, progress, retry_failed)
        plan = plan_run(study, options, method, store, executor.workers, retry_failed)
        journal, log = _announce(study, store, store_path, sampler, plan, method, out, log)
        watching.enter_context(watch_run(sampler, plan.total, progress=progress,
                                         stop_after_failures=stop_after_failures,
                                         retry_hint=_retry_hint(store_path)))
        t0 = time.perf_counter()
        result = _optimise(problem, method, options, sampler, log, x0, out)
        make_study_robust(study, result, sampler, log)
        timings["optimise_s"] = time.perf_counter() - t0
        n_opt = len(sampler.designs)
        timing = sampler.timing()
        # history: each simulation's objective in the order asked (NaN: failed), for the progress figure.
        result.update(parallel_accounting(sampler), history=[value for _, value in sampler.history.values()])
        log(f"  {_optimised_line(result)}; {rounds_text(timing)}")
        _check_some_succeeded(study, result, sampler, store_path)
        validation, references, sampling, failures = _validate_and_reference(study, result, options, sampler,
                                                                             timings, log, out, n_opt, timing)
        watching.close()  # the last progress line
    ground = _ground_truth(problem, out, truth, truth_step, timings)
    _line_model_verdict(result, validation, n_opt, log)
    result.update(validation=validation, outputs=references["optimum"]["outputs"])
    timings["total_s"] = time.perf_counter() - t_all
    run = StudyRun(study, options, result, validation, references, ground, timings, out, store_path, sampling,
                   failures, plan)
    t0 = time.perf_counter()
    write_outputs(run)
    timings["report_s"] = time.perf_counter() - t0
    journal.finish()
    return run


def _checked_places(study: Study, out: Path, options: SparseOptions, method: str, scheduler: str | None,
                    store_path: Path | None, force: bool) -> tuple[Path, Path]:
    """The run's arguments checked, and its output folder and store, before any simulation."""
    check_run(study, options, method, scheduler, store_path)
    if store_path is not None:
        check_store_folder(store_path)
    check_output_owner(out, study.name, study.problem.fingerprint(), force)
    out = check_output_folder(out)
    return out, Path(store_path) if store_path else out / "samples.sqlite"


def _validate_and_reference(study: Study, result: OptimizeResult, options: SparseOptions, sampler: Sampler,
                            timings: dict[str, float], log: Callable[[str], None], out: Path, n_opt: int,
                            timing: dict[str, Any]) -> tuple[Validation | None, dict, dict, list]:
    """After the optimisation: the held-out validation, the model saved, the reference designs simulated, and the
    accounting of the whole run's simulations and failures."""
    validation = _validate(result, study.problem, options, sampler, timings, log)
    n_val = len(sampler.designs) - n_opt
    if result.model is not None:
        result.model.save(out / "model.json")
    t0 = time.perf_counter()
    references = _references(study, result.x, sampler)
    timings["references_s"] = time.perf_counter() - t0
    # The rounds, waiting and computing of the whole run (validation and references included) and, apart, of
    # the optimisation alone.
    sampling = {**sampler.summary(), "optimisation": n_opt, "validation": n_val,
                "references": len(sampler.designs) - n_opt - n_val, "optimisation_timing": timing}
    failures = [(np.array(d), e) for d, e in sampler.failures.values()]
    return validation, references, sampling, failures


def _announce(study: Study, store: SampleStore, store_path: Path, sampler: Sampler, plan: RunPlan, method: str,
              out: Path, log: Callable[[str], None]) -> tuple[RunJournal, Callable[[str], None]]:
    """Print the study and its plan, and start the run's journal in the store (what `mechopt dashboard` reads);
    the log function returned also records each line there."""
    opening = [*study_header(study), f"  store {store_path}, {sampler.executor_description}", *plan.text()]
    for line in opening:
        log(line)
    journal = RunJournal(store_path, sampler.fingerprint, study.name,
                         describe_run(study.problem, plan, method, opening, out, store.count(sampler.fingerprint)))
    return journal, journal.tee(log)


def _retry_hint(store_path: Path) -> str:
    return f"--retry-failed (retry_failed=True) simulates them again (they are recorded in {store_path})"


def _optimise(problem, method: str, options: SparseOptions, sampler: Sampler, log: Callable[[str], None],
              x0: np.ndarray | None, out: Path) -> OptimizeResult:
    """The method's answer: replayed when every design it asked for is stored unchanged, else computed and kept."""
    share = options if x0 is None else checked_options(problem, method, options, options.budget, options.seed, x0)
    key = method_cache.run_key(problem, method, share, x0, sampler.batch_size)
    result = method_cache.replay(out, key, sampler)
    if result is None:
        result = run_method(problem, method, share, sampler, log, x0=x0)
        method_cache.save(out, key, sampler, result)
    else:
        log(f"  {method}: every one of its {len(sampler.designs)} simulations is in the store, unchanged: its "
            f"answer is replayed from {out / method_cache.CACHE_FILE}")
    return result


def plan_study(study: Study, options: SparseOptions, workers: int | None = None, scheduler: str | None = None,
               store_path: Path | None = None, retry_failed: bool = False, method: str = "sparse") -> RunPlan:
    """The plan of :func:`run_study` without running it: nothing is simulated and no file is written.

    Parameters are those of :func:`run_study`; ``store_path`` is read when it exists (a resumed run costs only the
    designs it lacks) and never created.
    """
    check_run(study, options, method)
    store = open_store_if_any(store_path) if store_path is not None else None
    try:
        return plan_run(study, options, method, store, _count_workers(workers, scheduler), retry_failed)
    finally:
        if store is not None:
            store.close()


def _line_model_verdict(result: OptimizeResult, validation: Validation | None, n_opt: int,
                        log: Callable[[str], None]) -> None:
    """The trust report of a run with a line model, and its simulations counted as the study's (the pipeline's
    designs, confirmation and refinement); nothing for a sparse run whose failures handed it to auto."""
    if result.get("pipeline") is not None:
        result["trust"] = study_trust(result.stages[0], result.pipeline.best, validation)
        result["nfev"] = n_opt
    if result.get("trust"):
        log(f"  trust: {result.trust['verdict']}")


def _check_some_succeeded(study: Study, result: OptimizeResult, sampler: Sampler, store_path: Path) -> None:
    """One line instead of a report of no design when every simulation failed (a broken command, a missing
    licence): the first reason, and where the failures are kept."""
    if np.all(np.isfinite(np.asarray(result.x, dtype=float))):
        return
    first = next(iter(sampler.failures.values()), (None, "no design was simulated"))[1]
    raise MechoptError(f"{study.name}: none of the {len(sampler.designs)} simulations succeeded, the first failed "
                       f"with: {first}; they are recorded in {store_path} (--retry-failed simulates them again)")


def check_run(study: Study, options: SparseOptions, method: str, scheduler: Any = None,
              store_path: Path | None = None) -> None:
    """What :func:`mechopt.minimize` checks before any work (the method for this budget, a feasible region), and
    before the output folder is made: a store path that is a folder, a scheduler nobody listens at."""
    check_method(method, study.problem.dim, study.name, options.budget, n_lines=options.n_lines)
    study.problem.check_region()
    if store_path is not None and Path(store_path).is_dir():
        raise InputError(f"--store {store_path} is a folder; expected the path of an SQLite file")
    if isinstance(scheduler, str):
        check_reachable(scheduler)


def plan_validate(study: Study, options: SparseOptions, model: Any = None, workers: int | None = None,
                  scheduler: str | None = None, store_path: Path | None = None,
                  retry_failed: bool = False) -> RunPlan:
    """The plan of ``mechopt validate`` (the line model's lines when there is no saved ``model``, then the held-out
    lines) without running it; ``store_path`` is read when it exists and never created."""
    store = open_store_if_any(store_path) if store_path is not None else None
    try:
        return plan_validation(study, options, store, _count_workers(workers, scheduler), model, retry_failed)
    finally:
        if store is not None:
            store.close()


def _count_workers(workers: int | None, scheduler: str | None) -> int:
    """Simulations a run will have at the same time: ``workers``, all cores, or the Dask cluster's workers."""
    if scheduler is not None:
        with make_executor(workers=workers, scheduler=scheduler) as executor:  # only to count the cluster's workers
            return executor.workers
    return workers or default_workers()


def _optimised_line(result: OptimizeResult) -> str:
    if result.get("pipeline") is not None:
        pipeline = result.pipeline
        return (f"{pipeline.message}; {pipeline.n_simulations} simulations ({pipeline.stages[0].n_samples} on the "
                "lines of the global model)")
    return f"{result.method}: {result.message}; {result.nfev} simulations"


def _validate(result: OptimizeResult, problem, options: SparseOptions, sampler: Sampler, timings: dict[str, float],
              log: Callable[[str], None]) -> Validation | None:
    """Held-out lines against the line model (``"sparse"`` only: the other methods have no model to check)."""
    n_lines, per_line = options.validation_plan()
    if n_lines == 0 or result.model is None:
        return None
    t0 = time.perf_counter()
    validation = validate(result.model, ModelSpace(problem), sampler, n_lines, per_line, options.seed,
                          f_min=result.fun)
    timings["validation_s"] = time.perf_counter() - t0
    unit = dict(problem.output_units).get(problem.objective, "")
    log(f"  validation: {validation.n_points} held-out simulations on {len(validation.lines)} lines, on top of the "
        f"budget; RMSE {validation.rmse:.4g}{(' ' + unit) if unit else ''} ({validation.relative_text(unit)}), "
        f"largest error {validation.max_error:.4g}{(' ' + unit) if unit else ''}")
    return validation


def _references(study: Study, x_opt: np.ndarray, sampler: Sampler) -> dict[str, dict[str, Any]]:
    """Every reference design of the study, and the optimum, with its outputs and feasibility."""
    problem = study.problem
    refs = {**study.reference_designs(), "optimum": np.asarray(x_opt, dtype=float)}
    # As written in the study file: a reference off the variables' grids (a continuous optimum) is what it is.
    records = sampler.records(np.vstack(list(refs.values())), desc="reference designs", snap=False)
    return {name: {"design": problem.design_dict(x), "status": r.status, "outputs": dict(r.outputs),
                   "error": r.error, "feasible": bool(problem.feasible(x)[0]), "allowed": bool(problem.on_grid(x)[0])}
            for (name, x), r in zip(refs.items(), records, strict=True)}


def _ground_truth(problem, out: Path, truth: bool, truth_step: float, timings: dict[str, float]) -> GroundTruth | None:
    """The brute-force optimum when asked for, or when an earlier run left it cached in ``out``."""
    truth_file = out / f"ground_truth_{truth_step:g}.json"
    if not (truth or truth_file.is_file()):
        return None
    t0 = time.perf_counter()
    ground = load_or_compute(problem, truth_file, truth_step, compute=truth)
    timings["ground_truth_s"] = time.perf_counter() - t0
    return ground


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
    lines += [f"against {name} (off the variables' grids, {obj} {c['objective']:.6g}): the grid costs "
              f"{c['cost_pct']:+.3f} %" for name, c in _grid_costs(run).items()]
    lines.append(_simulations_line(run))
    warning = reference_warning(run.references, obj, float(run.result.fun), dict(problem.output_units).get(obj, ""))
    return lines if warning is None else [*lines, warning]


def _grid_costs(run: StudyRun) -> dict[str, dict[str, float]]:
    """What holding the answer to the allowed designs cost against each feasible reference design off the grid."""
    summary = allowed_designs_summary(run.study.problem, int(run.options.budget), run.references,
                                      float(run.result.fun))
    return {} if summary is None else summary["cost_against"]


def _simulations_line(run: StudyRun) -> str:
    """Where the simulations went, against the budget: validation is on top of it, and says by how much."""
    s, budget = run.sampling, int(run.options.budget)
    stages = run.result.get("stages") or []
    on_lines = f"; {stages[0].n_samples} on the lines of the global model" if stages else ""
    val = (f"{s['validation']} to validate (held-out, on top of the budget: {s['validation'] / budget:.0%} of it)"
           if s["validation"] else "no validation")
    in_all = s["optimisation"] + s["validation"] + s["references"]
    expected = run.plan.seconds if run.plan is not None else None
    wall = f"wall time {run.timings['total_s']:.1f} s" + (
        "" if expected is None else f" (the plan expected about {duration_text(expected)} of simulation)")
    return (f"simulations: {s['optimisation']} to optimise (budget {budget}, method {run.result.method}{on_lines}), "
            f"{val}, {s['references']} more for the reference designs; {in_all} designs in all: {s['new']} new, "
            f"{s['reused']} reused from the store, {s['failed']} failed, {s['waited_for_other_runs']} computed by "
            f"another run; {s['executor']}; {rounds_text(s)}; {wall}; outputs in {run.out}")


def rounds_text(s: dict[str, Any]) -> str:
    """The parallel accounting of a run: rounds, the workers' idle share, waiting and computing.

    A round is as the plan printed before the run counts it: simulations one after the other, up to ``workers`` at
    a time (the sampler's ``waves``; 8 Sobol designs on 2 workers are 4 rounds).  The method's calls to the
    simulators (``rounds`` in ``result.json``, 1 for those 8) read as fewer rounds than the plan had promised.
    """
    if "waves" not in s:
        return "rounds not counted"
    return (f"{s['waves']} round{'' if s['waves'] == 1 else 's'} of simulations on {s['workers']} "
            f"worker{'' if s['workers'] == 1 else 's'} (idle {s['idle_share']:.0%} of their time), "
            f"{s['waiting_s']:.1f} s waiting for simulations, {s['method_s']:.1f} s of the method's own computing")
