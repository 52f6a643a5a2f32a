"""``mechopt compare``: mechopt against other optimizers at equal simulation budgets, on one or more studies."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from mechopt.cli.arguments import int_list, positive_float, positive_int
from mechopt.cli.study_arguments import load, study_name
from mechopt.errors import InputError

__all__ = ["add_parser", "run"]


def add_parser(sub, engines: tuple[str, ...]) -> None:
    """Add ``compare`` to the subcommands."""
    p = sub.add_parser("compare", help="mechopt against other optimizers at equal simulation budgets")
    what = ("study names or .toml paths, comma separated; also the multimodal test functions (default ventilator; "
            "`mechopt studies` lists them all)")
    p.add_argument("name", nargs="?", metavar="STUDIES", help=what)
    p.add_argument("--study", help="the same, as a flag")
    p.add_argument("--engine", choices=engines, help="simulation engine (default: the study's [compare] engine)")
    p.add_argument("--budgets", type=int_list, default=[50, 100, 200, 618, 1870],
                   help="simulation budgets, comma separated (default 50,100,200,618,1870)")
    p.add_argument("--seeds", type=positive_int, default=5, help="seeds per method and budget (default 5)")
    p.add_argument("--methods", help="comma-separated subset of the methods (default: all; `mechopt methods`; "
                   "auto, sparse and sparse-global are mechopt-auto, mechopt-sparse and mechopt-global)")
    p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
    p.add_argument("--truth-grid", type=positive_float, default=1.0, help="grid of the ground truth brute force")
    p.add_argument("--gp-max-budget", type=positive_int, metavar="N",
                   help="largest budget of the Gaussian-process methods (bayesian, smt_ego; default 200; "
                   "smt_ego 100 up to 3 variables, 60 at 4-5, 30 from 6): they refit at every call and take "
                   "minutes a run")
    p.set_defaults(func=run)


def _studies(args: argparse.Namespace, names: list[str]) -> list:
    """Every study loaded (with its ``[compare]`` engine) and checked before any run."""
    studies = []
    for name in names:
        study = load(argparse.Namespace(study=name, engine=args.engine))
        engine = args.engine or study.section("compare").get("engine")
        if engine:
            study = load(argparse.Namespace(study=name, engine=engine))
        if study.problem.objective_spec.k > 1:
            raise InputError(f"study {name!r} has {study.problem.objective_spec.k} objectives; compare scores one: "
                             "its multi-objective peers run in `python -m benchmarks.bench_pareto`")
        studies.append(study)
    return studies


def run(args: argparse.Namespace, rest: list[str]) -> int:
    """Run every method at every budget and seed on every study; write the tables and figures."""
    from mechopt.optimize.ground_truth import load_or_compute
    from mechopt.studies import comparison as cmp
    from mechopt.studies.runner import check_output_folder

    names = [n for n in study_name(args).split(",") if n]
    methods = cmp.method_names(args.methods)
    studies = _studies(args, names)
    cmp.check_methods(methods, args.budgets, args.gp_max_budget, [s.problem.dim for s in studies])
    base = Path(args.out or (f"{names[0]}-study" if len(names) == 1 else "compare"))
    needed, budgets, unfinished = {}, {}, {}
    for study in studies:
        out = check_output_folder(base if len(studies) == 1 else base / study.name)
        truth = cmp.known_truth(study.problem) or cmp.declared_truth(study)
        if truth is None:
            print(f"ground truth of {study.name} (brute force, grid {args.truth_grid:g}; cached in {out})")
            truth = load_or_compute(study.problem, out / f"ground_truth_{args.truth_grid:g}.json", args.truth_grid)
        print(f"{study.name}: optimum {study.problem.objective} {truth.fun:.6g} at "
              f"{study.problem.describe(np.array(truth.x))}")
        runs = cmp.compare(study, truth, args.budgets, args.seeds, methods, gp_max_budget=args.gp_max_budget)
        md, fig = cmp.write(runs, truth, out, study, args.seeds)
        print(md.read_text())
        print(f"table written to {md}, figure to {fig}")
        rows = cmp.table(runs, study.problem, truth)
        needed[study.name] = cmp.simulations_needed(rows)
        budgets[study.name] = cmp.largest_budgets(rows)
        unfinished[study.name] = cmp.unfinished_methods(rows)
    if len(studies) > 1:
        text, md, fig = cmp.write_headline(needed, budgets, base, unfinished)
        print(text)
        print(f"headline written to {md}, figure to {fig}")
    return 0
