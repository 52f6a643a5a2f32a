"""The ``mechopt`` command line.

Exit status: 0 success; 1 a user error (bad input, unknown study, malformed TOML, an unwritable output), printed as
one line on stderr; 3 for ``simulate`` when the design is infeasible (the answer is still printed: which constraint
fails, by how much); 130 when interrupted (Ctrl-C), with every finished simulation kept in the store.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from mechopt.errors import InfeasibleDesignError, InputError, MechoptError
from mechopt.surrogate.errors import SurrogateError

EXIT_ERROR = 1
EXIT_INFEASIBLE = 3
EXIT_INTERRUPTED = 130


class _Parser(argparse.ArgumentParser):
    """argparse with its errors on one line (no usage block): ``mechopt study: error: …`` and exit status 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _whole_number(minimum: int):
    """An argparse type: a whole number >= ``minimum``, or a one-line error naming the value."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"{text!r}: expected a whole number >= {minimum}")
        return value

    return parse


_positive_int = _whole_number(1)
_count = _whole_number(0)


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a finite number > 0")
    return value


def _int_list(text: str) -> list[int]:
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of integers") from None
    if not values or min(values) < 10:
        raise argparse.ArgumentTypeError(f"budgets {text!r}: expected integers >= 10")
    return values


def _load(args: argparse.Namespace, name: str | None = None):
    from mechopt.studies.catalogue import load_study

    return load_study(name or args.study, {"engine": getattr(args, "engine", None)})


def _cmd_simulate(args: argparse.Namespace, rest: list[str]) -> int:
    study = _load(args)
    problem = study.problem
    p = _Parser(prog=f"mechopt simulate --study {args.study}")
    for v in problem.variables:
        p.add_argument(f"--{v.name}", type=float, required=True, help=f"{v.label or v.name} ({v.unit})")
    values = p.parse_args(rest)
    x = np.array([getattr(values, v.name) for v in problem.variables], dtype=float)
    for v, value in zip(problem.variables, x, strict=True):
        if not math.isfinite(value):
            raise InputError(f"--{v.name} = {value}: expected a finite number ({v.unit})")
    if args.plot:
        from mechopt.sim.figure_file import figure_path

        figure_path(args.plot)
    margins = dict(zip(problem.constraints, problem.constraint_margins(x[None, :])[0].tolist(), strict=True))
    feasible = bool(problem.feasible(x)[0])
    message = _feasibility_message(problem, x, margins, feasible)
    try:
        outputs = problem.evaluate(x)
    except InfeasibleDesignError as exc:
        if args.json:
            print(json.dumps({"design": problem.design_dict(x), "feasible": False, "simulated": False,
                              "message": str(exc), "margins": margins}))
        else:
            print(message)
            print(f"not simulated: {exc}")
        return EXIT_INFEASIBLE
    if args.plot:
        figures = problem.figures({"design": x}, Path(args.plot).parent)
        files = list(figures.values())
        if files:
            Path(files[0]).replace(args.plot)
    if args.json:
        print(json.dumps({"design": problem.design_dict(x), "feasible": feasible, "simulated": True,
                          "margins": margins, "outputs": outputs, "engine": problem.settings().get("engine")}))
    else:
        print(message)
        engine = problem.settings().get("engine", "")
        print(f"engine {engine}: " + ", ".join(f"{k} = {v:.6g}" for k, v in outputs.items()
                                               if isinstance(v, float) and k in problem.outputs))
        if args.plot:
            print(f"figure written to {args.plot}")
    return 0 if feasible else EXIT_INFEASIBLE


def _feasibility_message(problem, x, margins: dict, feasible: bool) -> str:
    head = f"design {problem.describe(x)}"
    if not problem.in_box(x)[0]:
        head += " (outside the study's region)"
    failed = [f"{k} violated by {-v:.4g}" for k, v in margins.items() if not v >= 0]
    if feasible:
        return f"{head}: feasible (margins: " + ", ".join(f"{k} {v:.4g}" for k, v in margins.items()) + ")"
    return f"{head}: infeasible — " + ("; ".join(failed) if failed else "outside the region")


def _overrides(args: argparse.Namespace) -> dict:
    return {
        "plan": getattr(args, "plan", None),
        "n_lines": getattr(args, "lines_fit", None),
        "samples_per_line": getattr(args, "samples_per_line", None),
        "search_points": getattr(args, "search_points", None),
        "refine": False if getattr(args, "no_refine", False) else None,
        "validation_lines": getattr(args, "lines", None),
        "validation_points": getattr(args, "points_per_line", None),
        "budget": getattr(args, "budget", None),
        "seed": getattr(args, "seed", None),
    }


def _cmd_study(args: argparse.Namespace, rest: list[str]) -> int:
    from mechopt.cli.run_study import check_output_folder, run_study, study_options, summary_lines

    study = _load(args, args.name)
    options = study_options(study, _overrides(args))
    out = check_output_folder(Path(args.out or f"{study.name}-study"))
    run = run_study(study, out, options, workers=args.workers, scheduler=args.scheduler, store_path=args.store,
                    progress=not args.no_progress, truth=args.truth, truth_step=args.truth_grid,
                    retry_failed=args.retry_failed)
    print("\n".join(summary_lines(run)))
    print(f"report: {out / 'report.md'}")
    return 0


def _cmd_validate(args: argparse.Namespace, rest: list[str]) -> int:
    from mechopt.cli.run_study import check_output_folder, study_options
    from mechopt.optimize.sparse.model import ObjectiveModel
    from mechopt.optimize.sparse.sampler import Sampler
    from mechopt.optimize.sparse.space import ModelSpace
    from mechopt.optimize.sparse.stage import build_stage
    from mechopt.optimize.sparse.validate import validate
    from mechopt.report.plots import plot_validation
    from mechopt.runs.executors import make_executor
    from mechopt.runs.store import SampleStore

    study = _load(args)
    options = study_options(study, _overrides(args))
    out = check_output_folder(Path(args.out or f"{study.name}-study"))
    store_path = Path(args.store) if args.store else out / "samples.sqlite"
    space = ModelSpace(study.problem)
    model_path = out / "model.json"
    model = None
    if model_path.is_file() and not args.refit:
        model = ObjectiveModel.load(model_path)
        if model.variables and tuple(model.variables) != study.problem.names:
            raise InputError(f"{model_path} models {list(model.variables)}, not this study's "
                             f"{list(study.problem.names)}; pass --refit")
    f_min = _best_known(out, study)
    with SampleStore(store_path) as store, make_executor(args.workers, args.scheduler) as executor:
        sampler = Sampler(study.problem, store, executor, not args.no_progress)
        fit_lines = None
        if model is None:
            stage = build_stage("global", space, options, sampler, options.n_lines, options.samples_per_line,
                                options.search_points, paper=options.plan == "paper")
            model = stage.model
            model.save(model_path)
            fit_lines = list(zip(stage.line_designs, stage.line_values, strict=True))
            print(f"model fitted on {stage.n_samples} samples and saved to {model_path}")
            f_min = min(f_min, stage.simulated) if np.isfinite(f_min) else stage.simulated
        else:
            print(f"model read from {model_path}")
        if not np.isfinite(f_min):
            raise InputError(f"no best design known in {out}: run `mechopt study` first, or pass --refit")
        val = validate(model, space, sampler, options.validation_lines, options.validation_points, options.seed,
                       f_min=f_min)
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
    return 0


def _best_known(out: Path, study) -> float:
    """The run's best simulated objective from ``result.json`` (one definition of f_min everywhere)."""
    path = out / "result.json"
    if not path.is_file():
        return float("nan")
    try:
        return float(json.loads(path.read_text())["optimum"]["objective"])
    except (OSError, ValueError, KeyError, TypeError):
        raise InputError(f"{path} is damaged (not a mechopt result); rerun `mechopt study {study.name}`") from None


def _cmd_feasible(args: argparse.Namespace, rest: list[str]) -> int:
    from mechopt.cli.run_study import check_output_folder
    from mechopt.report.plots import plot_feasible_3d, plot_feasible_slices

    study = _load(args)
    problem = study.problem
    out = check_output_folder(Path(args.out or f"{study.name}-study"))
    marks = study.reference_designs()
    result = out / "result.json"
    if result.is_file():
        try:
            d = json.loads(result.read_text())["optimum"]["design"]
            marks["optimum"] = np.array([d[n] for n in problem.names])
        except (OSError, ValueError, KeyError, TypeError):
            raise InputError(f"{result} is damaged (not a mechopt result); rerun `mechopt study {study.name}`") \
                from None
    files = [plot_feasible_slices(problem, out / "figures" / "feasible_slices_all_designs.png", marks=marks,
                                  n_slices=5)]
    if problem.dim == 3:
        files.append(plot_feasible_3d(problem, out / "figures" / "feasible_3d_all_designs.png", marks=marks))
    rng = np.random.default_rng(0)
    cloud = rng.uniform(problem.bounds[:, 0], problem.bounds[:, 1], size=(200_000, problem.dim))
    print(f"{100 * problem.feasible(cloud).mean():.1f} % of the region is feasible")
    for name, x in marks.items():
        margins = dict(zip(problem.constraints, problem.constraint_margins(x[None, :])[0].tolist(), strict=True))
        print(_feasibility_message(problem, x, margins, bool(problem.feasible(x)[0])).replace("design", name, 1))
    print("figures written to " + " and ".join(map(str, files)))
    return 0


def _cmd_truth(args: argparse.Namespace, rest: list[str]) -> int:
    from mechopt.cli.run_study import check_output_folder
    from mechopt.optimize.ground_truth import load_or_compute

    study = _load(args)
    out = check_output_folder(Path(args.out or f"{study.name}-study"))
    truth = load_or_compute(study.problem, out / f"ground_truth_{args.truth_grid:g}.json", args.truth_grid)
    print(f"ground truth of {study.name}: {study.problem.describe(np.array(truth.x))}, {study.problem.objective} "
          f"{truth.fun:.6g} ({truth.n_feasible} feasible of {truth.n_evaluated} grid designs, "
          f"{truth.wall_time_s:.1f} s; cached in {out})")
    return 0


def _cmd_init(args: argparse.Namespace, rest: list[str]) -> int:
    import shutil

    from mechopt.studies.catalogue import STUDIES_DIR, available_studies

    folder = STUDIES_DIR / args.name.replace("-", "_")
    if not (folder / "study.toml").is_file():
        raise InputError(f"unknown study {args.name!r}; expected one of {', '.join(available_studies())}")
    to = Path(args.to or f"my-{args.name}")
    if to.exists() and (not to.is_dir() or any(to.iterdir())):
        raise InputError(f"{to} exists and is not an empty folder; name another with --to")
    try:
        to.mkdir(parents=True, exist_ok=True)
        copied = []
        for f in sorted(folder.iterdir()):
            if f.is_file() and f.suffix in (".toml", ".csv", ".md", ".json", ".py") and f.name != "__init__.py":
                shutil.copy2(f, to / f.name)
                copied.append(f.name)
    except OSError as exc:
        raise InputError(f"cannot copy the study into {to}: {exc.strerror or exc}") from None
    print(f"copied {', '.join(copied)} to {to}; edit {to / 'study.toml'} (give it a new name) and run "
          f"`mechopt study {to / 'study.toml'}`")
    return 0


def _cmd_compare(args: argparse.Namespace, rest: list[str]) -> int:
    from mechopt.cli import compare as cmp
    from mechopt.cli.run_study import check_output_folder
    from mechopt.optimize.ground_truth import load_or_compute

    names = [n for n in args.study.split(",") if n]
    methods = args.methods.split(",") if args.methods else None
    studies = []
    for name in names:  # every study loaded and checked before any run
        args.study = name
        engine = args.engine
        study = _load(args)
        engine = engine or study.section("compare").get("engine")
        if engine:
            study = _load(argparse.Namespace(study=name, engine=engine))
        studies.append(study)
    base = Path(args.out or (f"{names[0]}-study" if len(names) == 1 else "compare"))
    needed, budgets = {}, {}
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
    if len(studies) > 1:
        text = cmp.headline(needed, budgets)
        (base / "headline.md").write_text(text)
        fig = cmp.plot_headline(needed, budgets, base / "figures" / "compare_headline.png")
        print(text)
        print(f"headline written to {base / 'headline.md'}, figure to {fig}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``mechopt`` with all its subcommands."""
    from mechopt.sim.fourbar.simulate import ENGINES

    parser = _Parser(
        prog="mechopt",
        description="Globally optimal mechanism dimensions from few motion simulations (lengths in mm).",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    def study_arg(p: argparse.ArgumentParser) -> None:
        p.add_argument("--study", default="ventilator", help="study name or path of a study .toml (default ventilator)")
        p.add_argument("--engine", choices=ENGINES, help="simulation engine (default: the study's)")

    p = sub.add_parser("simulate", help="simulate one design: feasibility with margins and the outputs; the "
                       "variables are flags named after the study's (--oa 53 --ab 65 --bc 282 for a four-bar)")
    study_arg(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE", help="write the mechanism's figure of the design to FILE (png)")
    p.set_defaults(func=_cmd_simulate, extra=True)

    def run_options(p: argparse.ArgumentParser) -> None:
        p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
        p.add_argument("--workers", type=_positive_int, help="local worker processes (default: all cores)")
        p.add_argument("--scheduler", metavar="ADDR", help="Dask scheduler address tcp://HOST:PORT (dask extra)")
        p.add_argument("--store", metavar="FILE", help="SQLite sample store (default: DIR/samples.sqlite)")
        p.add_argument("--plan", choices=("auto", "paper"),
                       help="line plan: automatic, or the paper's Δ, spacing, origin and 7 lines")
        p.add_argument("--lines-fit", type=_positive_int, help="lines of the global model (ventilator: 21)")
        p.add_argument("--samples-per-line", type=_positive_int, help="target samples per line of the global model")
        p.add_argument("--search-points", type=_positive_int, help="grid points of the exhaustive search")
        p.add_argument("--budget", type=_positive_int, help="most simulations to optimise (default: the study's)")
        p.add_argument("--seed", type=_count, help="seed of the planner and the validation lines")
        p.add_argument("--no-refine", action="store_true", help="report the model's candidate without local refinement")
        p.add_argument("--points-per-line", type=_positive_int, help="points per held-out line")
        p.add_argument("--retry-failed", action="store_true", help="simulate again designs whose simulation failed")
        p.add_argument("--no-progress", action="store_true", help="no progress bars")

    p = sub.add_parser("study", help="run a study: sample, fit, search, refine, validate, report")
    p.add_argument("name", nargs="?", default="ventilator", help="study name or .toml path (default: ventilator)")
    p.add_argument("--engine", choices=ENGINES, help="simulation engine (default: the study's)")
    run_options(p)
    p.add_argument("--lines", type=_count, help="held-out validation lines (default 10; 0: none)")
    p.add_argument("--truth", action="store_true", help="also brute-force the ground truth (cached)")
    p.add_argument("--truth-grid", type=_positive_float, default=1.0, help="its grid step (the variables' unit)")
    p.set_defaults(func=_cmd_study)

    p = sub.add_parser("validate", help="simulate held-out lines and compare them with the saved model")
    study_arg(p)
    run_options(p)
    p.add_argument("--lines", type=_positive_int, help="held-out lines (default 10)")
    p.add_argument("--refit", action="store_true", help="refit the model even if DIR/model.json exists")
    p.set_defaults(func=_cmd_validate)

    p = sub.add_parser("truth", help="brute-force a study's true optimum (a fast batch evaluator), cached")
    study_arg(p)
    p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
    p.add_argument("--truth-grid", type=_positive_float, default=1.0, help="grid step (the variables' unit)")
    p.set_defaults(func=_cmd_truth)

    p = sub.add_parser("compare", help="mechopt against other optimizers at equal simulation budgets")
    p.add_argument("--study", default="ventilator", help="study names or .toml paths, comma separated; also the "
                   "multimodal test functions (hartmann3, cosine_bowl3, branin, six_hump_camel, himmelblau_disc)")
    p.add_argument("--engine", choices=ENGINES, help="simulation engine (default: the study's [compare] engine)")
    p.add_argument("--budgets", type=_int_list, default=[50, 100, 200, 618, 1870],
                   help="simulation budgets, comma separated (default 50,100,200,618,1870)")
    p.add_argument("--seeds", type=_positive_int, default=5, help="seeds per method and budget (default 5)")
    p.add_argument("--methods", help="comma-separated subset of the methods (default: all)")
    p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
    p.add_argument("--truth-grid", type=_positive_float, default=1.0, help="grid of the ground truth brute force")
    p.add_argument("--gp-max-budget", type=_positive_int, metavar="N",
                   help="largest budget of the Gaussian-process methods (bayesian, smt_ego; default 200 and 100): "
                   "they refit at every call and take minutes a run")
    p.set_defaults(func=_cmd_compare)

    p = sub.add_parser("init", help="copy a packaged study (its TOML and data) to start a study of your own")
    p.add_argument("name", help="the packaged study to copy (e.g. ventilator)")
    p.add_argument("--to", metavar="DIR", help="folder to copy it into (default: my-NAME; must be new or empty)")
    p.set_defaults(func=_cmd_init)

    p = sub.add_parser("feasible", help="plot the feasible region with every reference design")
    study_arg(p)
    p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
    p.set_defaults(func=_cmd_feasible)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``mechopt``; returns the exit status (see the module docstring)."""
    parser = build_parser()
    args, rest = parser.parse_known_args(argv)
    if rest and not getattr(args, "extra", False):
        parser.error(f"unrecognized arguments: {' '.join(rest)}")
    try:
        return int(args.func(args, rest))
    except (MechoptError, SurrogateError) as exc:
        print(f"mechopt: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("mechopt: interrupted; every simulation finished so far is kept in the store", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
