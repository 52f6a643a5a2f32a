"""``mechopt study``'s ``--objective`` and ``--limit``, and the run of a study with several objectives or limits."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path
from typing import Any

__all__ = ["add_trade_off_options", "apply_trade_off", "run_trade_off_command"]


def add_trade_off_options(p: argparse.ArgumentParser) -> None:
    """``--objective`` and ``--limit`` (repeatable)."""
    p.add_argument("--objective", metavar="NAMES",
                   help="output(s) to minimise, comma-separated, a leading '-' maximises one (e.g. "
                   "t_rms,-toggle_margin_deg: a Pareto front); write it as --objective=-name when it starts with '-'")
    p.add_argument("--limit", action="append", metavar="LIMIT",
                   help="a limit on a simulated output: 'name<=value', 'name>=value' or 'low<=name<=high' (repeatable)")


def apply_trade_off(study: Any, args: argparse.Namespace) -> Any:
    """The study with the command line's objectives and limits (itself when neither flag is given)."""
    from mechopt.studies.trade_off_section import command_line_trade_off

    if not getattr(args, "objective", None) and not getattr(args, "limit", None):
        return study
    problem = command_line_trade_off(study.problem, args.objective, args.limit)
    return dataclasses.replace(study, problem=problem)


def run_trade_off_command(study: Any, args: argparse.Namespace) -> int:
    """Run a trade-off study (:mod:`mechopt.studies.trade_off_study`) and print where its report is."""
    from mechopt.optimize.arguments import check_budget, check_workers
    from mechopt.studies.trade_off_study import DEFAULT_TRADE_OFF_BUDGET, run_trade_off_study

    budget = args.budget if args.budget is not None else DEFAULT_TRADE_OFF_BUDGET
    check_budget(budget)
    check_workers(args.workers)
    run = run_trade_off_study(study, Path(args.out or f"{study.name}-trade-off"), budget, seed=args.seed or 0,
                              workers=args.workers, store=args.store, progress=not args.no_progress)
    r = run.result
    print(r.message)
    if r.success and study.problem.objective_spec.k == 1:
        print(f"answer: {study.problem.describe(r.x)}, "
              + ", ".join(f"{k} = {v:.6g}" for k, v in r.outputs.items() if isinstance(v, float)))
    print(f"report: {run.out / 'report.md'}")
    return 0
