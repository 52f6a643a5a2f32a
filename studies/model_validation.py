"""Validate a study's line model on held-out lines (``mechopt validate``): the model the run saved (or one fitted
now), simulated along lines it was not fitted on, the errors written to ``validation.json`` and a figure."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError, MechoptError
from mechopt.optimize.sparse.options import SparseOptions
from mechopt.studies.catalogue import Study

__all__ = ["best_known", "saved_model", "simulate_validation", "write_validation"]


def saved_model(model_path: Path, study: Study, refit: bool) -> Any:
    """The model a study run saved, or None when there is none or a refit is asked for."""
    from mechopt.optimize.sparse.model import ObjectiveModel

    if not model_path.is_file() or refit:
        return None
    model = ObjectiveModel.load(model_path)
    if model.variables and tuple(model.variables) != study.problem.names:
        raise InputError(f"{model_path} models {list(model.variables)}, not this study's "
                         f"{list(study.problem.names)}; pass --refit")
    return model


def simulate_validation(study: Study, options: SparseOptions, out: Path, store_path: Path, model: Any, f_min: float,
                        workers: int | None = None, scheduler: Any = None, progress: bool = True,
                        retry_failed: bool = False, log: Callable[[str], None] = print) -> tuple:
    """Fit the line model if there is none (saved beside the run), then simulate the held-out lines.

    Returns
    -------
    tuple
        The validation, the model, the lines it was fitted on (None: read) and a line saying what was simulated and
        what reused.
    """
    from mechopt.optimize.sparse.sampler import Sampler
    from mechopt.optimize.sparse.space import ModelSpace
    from mechopt.optimize.sparse.stage import build_stage
    from mechopt.optimize.sparse.validate import validate
    from mechopt.runs.executors import make_executor
    from mechopt.runs.store import SampleStore
    from mechopt.studies.plan import plan_validation

    space = ModelSpace(study.problem)
    fit_lines = None
    with SampleStore(store_path) as store, make_executor(workers, scheduler) as executor:
        # What the run will simulate, before it does: without a saved model that is a whole line model first.
        log("\n".join(plan_validation(study, options, store, executor.workers, model, retry_failed).text()))
        sampler = Sampler(study.problem, store, executor, progress, retry_failed=retry_failed)
        if model is None:
            stage = build_stage("global", space, options, sampler, options.n_lines, options.samples_per_line,
                                options.search_points, paper=options.plan == "paper")
            model = stage.model
            model.save(out / "model.json")
            fit_lines = list(zip(stage.line_designs, stage.line_values, strict=True))
            log(f"model fitted on {stage.n_samples} samples and saved to {out / 'model.json'}")
            f_min = min(f_min, stage.simulated) if np.isfinite(f_min) else stage.simulated
        else:
            log(f"model read from {out / 'model.json'}")
        val = validate(model, space, sampler, options.validation_lines, options.validation_points, options.seed,
                       f_min=f_min)
    failed = f", {len(sampler.failures)} failed" if sampler.failures else ""
    return val, model, fit_lines, (f"simulations: {sampler.n_computed} new, {sampler.n_cached} reused from the store"
                                   f"{failed}, {sampler.n_waited} computed by another run")


def best_known(out: Path, study: Study) -> float:
    """The run's best simulated objective from ``result.json`` (one definition of f_min everywhere)."""
    path = out / "result.json"
    if not path.is_file():
        return float("nan")
    try:
        return float(json.loads(path.read_text())["optimum"]["objective"])
    except (OSError, ValueError, KeyError, TypeError):
        raise InputError(f"{path} is damaged (not a mechopt result); rerun `mechopt study {study.name}`") from None


def write_validation(val: Any, model: Any, fit_lines: list | None, study: Study, out: Path) -> Path:
    """Write ``validation.json`` and the figure of the held-out lines into ``out``; returns the figure's path.

    Raises
    ------
    MechoptError
        When no held-out line could be placed inside the model's hull.
    """
    from mechopt.report.plots import plot_validation

    if val.n_points == 0:
        raise MechoptError("no held-out line could be placed inside the model's hull; nothing validated")
    figure = plot_validation(val.lines, out / "figures" / "validation_heldout.png", fit_lines, model,
                             label=study.problem.objective)
    (out / "validation.json").write_text(json.dumps(val.summary(), indent=2))
    return figure
