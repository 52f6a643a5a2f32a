"""``mechopt study``: run a whole study (optimise, validate, evaluate the reference designs, report)."""

from __future__ import annotations

import argparse
from pathlib import Path

from mechopt.cli.arguments import count, float_list, positive_float
from mechopt.cli.study_arguments import add_method_option, add_run_options, add_study_argument, load, overrides
from mechopt.cli.trade_off_options import add_trade_off_options, apply_trade_off, run_trade_off_command

__all__ = ["add_parser", "run"]


def add_parser(sub, engines: tuple[str, ...]) -> None:
    """Add ``study`` to the subcommands."""
    p = sub.add_parser("study", help="run a study: sample, fit, search, refine, validate, report")
    add_study_argument(p, engines)
    add_method_option(p)
    add_run_options(p)
    p.add_argument("--lines", type=count, help="most held-out validation lines (default 10; 0: no validation)")
    p.add_argument("--validation", type=count, metavar="N",
                   help="held-out simulations on top of the budget (default: 20 %% of the budget; 300 = the "
                   "ventilator's full 10 lines x 30 of earlier versions; 0: no validation)")
    p.add_argument("--dry-run", action="store_true",
                   help="print the plan (stages, simulations, expected wall time) and simulate nothing")
    p.add_argument("--x0", action="append", type=float_list, metavar="VALUES",
                   help="a design to start from, its variables' values comma-separated in the order and units of "
                   "`mechopt study STUDY --dry-run`; repeat for several; simulated first and counted in the budget: "
                   "the answer is never worse")
    p.add_argument("--force", action="store_true", help="use --out even if it holds another study's or problem's "
                   "results (their report, result.json, model and figures are removed first; the store is kept)")
    p.add_argument("--truth", action="store_true", help="also brute-force the ground truth (cached)")
    p.add_argument("--truth-grid", type=positive_float, default=1.0, help="its grid step (the variables' unit)")
    add_trade_off_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace, rest: list[str]) -> int:
    """Run the study named on the command line and print its summary."""
    from mechopt.optimize.arguments import DEFAULT_METHOD, check_budget, check_method, check_x0
    from mechopt.optimize.minimize import checked_options
    from mechopt.studies.runner import plan_study, run_study, study_options, summary_lines

    study = apply_trade_off(load(args), args)
    if study.problem.trade_off and not args.dry_run:
        return run_trade_off_command(study, args)
    args.method = args.method or study.method or DEFAULT_METHOD
    if args.budget is not None:
        check_budget(args.budget)
    check_method(args.method, study.problem.dim, study.name)
    # The options' notes wait for the budget check: a refused budget prints nothing but its one line.
    notes: list[str] = []
    options = study_options(study, overrides(args), log=notes.append)
    check_method(args.method, study.problem.dim, study.name, options.budget, n_lines=options.n_lines)
    # One --x0 is one design, as minimize's x0 of shape (d,): its errors then read the same.
    x0 = check_x0(study.problem, args.x0[0] if args.x0 and len(args.x0) == 1 else args.x0, options.budget)
    if x0 is not None:
        # Refused here, before any output, when x0 leaves the method less than its minimum.
        left = checked_options(study.problem, args.method, options, options.budget, options.seed, x0).budget
        notes.append(f"x0: {x0.shape[0]} design(s) simulated first, counted in the budget of {options.budget} (the "
                     f"method has {left})")
    for note in notes:
        print(note)
    out_arg = Path(args.out or f"{study.name}-study")
    if args.dry_run:
        store = Path(args.store) if args.store else out_arg / "samples.sqlite"
        plan = plan_study(study, options, workers=args.workers, scheduler=args.scheduler, store_path=store,
                          retry_failed=args.retry_failed, method=args.method)
        from mechopt.studies.run_header import study_header

        print("\n".join([*study_header(study), f"  store {store}", *plan.text()]))
        print("dry run: nothing simulated")
        return 0
    # run_study checks the run (store, scheduler, feasible region) before it makes the output folder.
    run = run_study(study, out_arg, options, workers=args.workers, scheduler=args.scheduler, store_path=args.store,
                    progress=not args.no_progress, truth=args.truth, truth_step=args.truth_grid,
                    retry_failed=args.retry_failed, method=args.method, x0=x0,
                    stop_after_failures=args.stop_after_failures, force=args.force)
    print("\n".join(summary_lines(run)))
    print(f"report: {run.out / 'report.md'}")
    return 0

