"""``mechopt validate``: simulate held-out lines and compare them with a study's saved line model."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from mechopt.cli.arguments import positive_int
from mechopt.cli.study_arguments import add_run_options, add_study_argument, load, overrides
from mechopt.errors import InputError

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


def run(args: argparse.Namespace, rest: list[str]) -> int:
    """Validate the saved (or a refitted) model on held-out lines; print the errors, write the figure."""
    from mechopt.optimize.arguments import check_budget
    from mechopt.studies.model_validation import best_known, saved_model, simulate_validation, write_validation
    from mechopt.studies.runner import check_output_folder, plan_validate, study_options

    study = load(args)
    if args.budget is not None:
        check_budget(args.budget)
    options = study_options(study, overrides(args))
    out = Path(args.out or f"{study.name}-study")
    store_path = Path(args.store) if args.store else out / "samples.sqlite"
    model = saved_model(out / "model.json", study, args.refit)
    f_min = best_known(out, study)
    if model is not None and not np.isfinite(f_min):
        raise InputError(f"no best design known in {out}: run `mechopt study` first, or pass --refit")
    if args.dry_run:
        plan = plan_validate(study, options, model, args.workers, args.scheduler, store_path, args.retry_failed)
        print("\n".join([*plan.text(), "dry run: nothing simulated"]))
        return 0
    val, model, fit_lines, counts = simulate_validation(
        study, options, check_output_folder(out), store_path, model, f_min, args.workers, args.scheduler,
        not args.no_progress, args.retry_failed)
    figure = write_validation(val, model, fit_lines, study, out)
    low = (f", {val.rmse_low:.4g} where {study.problem.objective} is <= 2 × the best simulated value"
           if math.isfinite(val.rmse_low) else "")
    print(f"{val.n_points} held-out simulations on {len(val.lines)} lines: RMSE {val.rmse:.4g} "
          f"({val.relative_text()}){low}, max error {val.max_error:.4g}")
    print(f"figure written to {figure}")
    print(counts)
    return 0
