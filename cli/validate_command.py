"""``mechopt validate``: simulate held-out lines and compare them with a study's saved line model."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from mechopt.cli.arguments import positive_int
from mechopt.cli.study_arguments import add_run_options, add_study_argument, load, overrides
from mechopt.errors import InputError, MechoptError

__all__ = ["add_parser", "run"]


def add_parser(sub, engines: tuple[str, ...]) -> None:
    """Add ``validate`` to the subcommands."""
    p = sub.add_parser("validate", help="simulate held-out lines and compare them with the saved model")
    add_study_argument(p, engines)
    add_run_options(p)
    p.add_argument("--lines", type=positive_int, help="held-out lines (default 10)")
    p.add_argument("--refit", action="store_true", help="refit the model even if DIR/model.json exists")
    p.add_argument("--dry-run", action="store_true",
                   help="print the plan (simulations and expected wall time) and simulate nothing")
    p.set_defaults(func=run)


def _saved_model(model_path: Path, study, refit: bool):
    """The model a study run saved, or None when there is none or a refit is asked for."""
    from mechopt.optimize.sparse.model import ObjectiveModel

    if not model_path.is_file() or refit:
        return None
    model = ObjectiveModel.load(model_path)
    if model.variables and tuple(model.variables) != study.problem.names:
        raise InputError(f"{model_path} models {list(model.variables)}, not this study's "
                         f"{list(study.problem.names)}; pass --refit")
    return model


def run(args: argparse.Namespace, rest: list[str]) -> int:
    """Validate the saved (or a refitted) model on held-out lines; print the errors, write the figure."""
    from mechopt.optimize.arguments import check_budget
    from mechopt.report.plots import plot_validation
    from mechopt.studies.runner import check_output_folder, plan_validate, study_options

    study = load(args)
    if args.budget is not None:
        check_budget(args.budget)
    options = study_options(study, overrides(args))
    out = Path(args.out or f"{study.name}-study")
    store_path = Path(args.store) if args.store else out / "samples.sqlite"
    model = _saved_model(out / "model.json", study, args.refit)
    f_min = _best_known(out, study)
    if model is not None and not np.isfinite(f_min):
        raise InputError(f"no best design known in {out}: run `mechopt study` first, or pass --refit")
    if args.dry_run:
        plan = plan_validate(study, options, model, args.workers, args.scheduler, store_path, args.retry_failed)
        print("\n".join([*plan.text(), "dry run: nothing simulated"]))
        return 0
    val, model, fit_lines, counts = _simulate(args, study, options, check_output_folder(out), store_path, model, f_min)
    if val.n_points == 0:
        raise MechoptError("no held-out line could be placed inside the model's hull; nothing validated")
    figure = plot_validation(val.lines, out / "figures" / "validation_heldout.png", fit_lines, model,
                             label=study.problem.objective)
    (out / "validation.json").write_text(json.dumps(val.summary(), indent=2))
    low = (f", {val.rmse_low:.4g} where {study.problem.objective} is <= 2 × the best simulated value"
           if math.isfinite(val.rmse_low) else "")
    print(f"{val.n_points} held-out simulations on {len(val.lines)} lines: RMSE {val.rmse:.4g} "
          f"({val.relative_text()}){low}, max error {val.max_error:.4g}")
    print(f"figure written to {figure}")
    print(counts)
    return 0


def _simulate(args: argparse.Namespace, study, options, out: Path, store_path: Path, model, f_min: float):
    """Fit the line model if there is none (saved beside the run), then simulate the held-out lines; the validation,
    the model, the lines it was fitted on (None: read) and a line saying what was simulated and what reused."""
    from mechopt.optimize.sparse.sampler import Sampler
    from mechopt.optimize.sparse.space import ModelSpace
    from mechopt.optimize.sparse.stage import build_stage
    from mechopt.optimize.sparse.validate import validate
    from mechopt.runs.executors import make_executor
    from mechopt.runs.store import SampleStore
    from mechopt.studies.plan import plan_validation

    space = ModelSpace(study.problem)
    fit_lines = None
    with SampleStore(store_path) as store, make_executor(args.workers, args.scheduler) as executor:
        # What the run will simulate, before it does: without a saved model that is a whole line model first.
        print("\n".join(plan_validation(study, options, store, executor.workers, model, args.retry_failed).text()))
        sampler = Sampler(study.problem, store, executor, not args.no_progress, retry_failed=args.retry_failed)
        if model is None:
            stage = build_stage("global", space, options, sampler, options.n_lines, options.samples_per_line,
                                options.search_points, paper=options.plan == "paper")
            model = stage.model
            model.save(out / "model.json")
            fit_lines = list(zip(stage.line_designs, stage.line_values, strict=True))
            print(f"model fitted on {stage.n_samples} samples and saved to {out / 'model.json'}")
            f_min = min(f_min, stage.simulated) if np.isfinite(f_min) else stage.simulated
        else:
            print(f"model read from {out / 'model.json'}")
        val = validate(model, space, sampler, options.validation_lines, options.validation_points, options.seed,
                       f_min=f_min)
    failed = f", {len(sampler.failures)} failed" if sampler.failures else ""
    return val, model, fit_lines, (f"simulations: {sampler.n_computed} new, {sampler.n_cached} reused from the store"
                                   f"{failed}, {sampler.n_waited} computed by another run")


def _best_known(out: Path, study) -> float:
    """The run's best simulated objective from ``result.json`` (one definition of f_min everywhere)."""
    path = out / "result.json"
    if not path.is_file():
        return float("nan")
    try:
        return float(json.loads(path.read_text())["optimum"]["objective"])
    except (OSError, ValueError, KeyError, TypeError):
        raise InputError(f"{path} is damaged (not a mechopt result); rerun `mechopt study {study.name}`") from None
