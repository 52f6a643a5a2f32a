"""The ``mechopt`` command line.

Exit status: 0 success; 1 a user error (bad input, unknown study, malformed TOML), printed as one line on stderr;
3 for ``simulate`` when the design is infeasible (the answer is still printed: which constraint fails, by how much).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from mechopt.errors import InfeasibleDesignError, MechoptError
from mechopt.surrogate.errors import SurrogateError

if TYPE_CHECKING:
    from .workflow import SurrogateOptions

EXIT_ERROR = 1
EXIT_INFEASIBLE = 3


def _add_study(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--study", default="ventilator", help="study name or path of a study .toml (default: ventilator)"
    )


def _cmd_simulate(args: argparse.Namespace) -> int:
    from mechopt.sim.fourbar.feasibility import check_feasibility
    from mechopt.sim.fourbar.kinematics import check_design
    from mechopt.sim.fourbar.simulate import simulate

    from .definition import load_study

    design = check_design((args.oa, args.ab, args.bc))
    study = load_study(args.study)
    report = check_feasibility(design, study.mechanism)
    try:
        result = simulate(design, study.mechanism, engine=args.engine)
    except InfeasibleDesignError:
        if args.json:
            print(json.dumps({"design_mm": dict(zip(("oa", "ab", "bc"), design.tolist(), strict=True)),
                              "feasible": False, "movable": False, "message": report.message(0),
                              "margins": report.margins(0)}))
        else:
            print(report.message(0))
            print("not simulated: the design cannot be driven through the stroke")
        return EXIT_INFEASIBLE
    if args.plot:
        from .plots import plot_simulation

        plot_simulation(result, study, args.plot)
    if args.json:
        print(json.dumps(result.summary()))
    else:
        print(result.message)
        print(f"engine {result.engine}: T_RMS = {result.t_rms:.4f} N·m, T_max = {result.t_max:.4f} N·m "
              f"({result.t.size} samples, step {result.dt * 1e3:.3f} ms, {result.wall_time_s * 1e3:.0f} ms)")
        if args.plot:
            print(f"figure written to {args.plot}")
    return 0 if result.feasible else EXIT_INFEASIBLE


def _options(args: argparse.Namespace, study) -> SurrogateOptions:
    from .workflow import SurrogateOptions

    overrides = {
        "plan": getattr(args, "plan", None),
        "n_lines": getattr(args, "lines_fit", None),
        "samples_per_line": getattr(args, "samples_per_line", None),
        "search_points": getattr(args, "search_points", None),
        "refine": False if getattr(args, "no_refine", False) else None,
        "validation_lines": getattr(args, "lines", None),
        "validation_points": getattr(args, "points_per_line", None),
    }
    return SurrogateOptions.from_study(study.section("surrogate"), overrides)


def _cmd_study(args: argparse.Namespace) -> int:
    from .definition import load_study
    from .run import run_study, summary_lines

    study = load_study(args.name)
    options = _options(args, study)
    out = Path(args.out or f"{study.name}-study")
    run = run_study(study, out, options, engine=args.engine, workers=args.workers, scheduler=args.scheduler,
                    store_path=args.store, progress=not args.no_progress, truth_step_mm=args.truth_grid)
    print("\n".join(summary_lines(run)))
    print(f"report: {out / 'report.md'}")
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    from .definition import load_study
    from .plots import plot_validation
    from .run import make_space, open_sampler
    from .workflow import ObjectiveModel, build_stage, validate

    study = load_study(args.study)
    options = _options(args, study)
    out = Path(args.out or f"{study.name}-study")
    out.mkdir(parents=True, exist_ok=True)
    store_path = Path(args.store) if args.store else out / "samples.sqlite"
    space = make_space(study, options)
    store, executor, sampler = open_sampler(study, args.engine, store_path, args.workers, args.scheduler,
                                            not args.no_progress)
    with store, executor:
        model_path = out / "model.json"
        fit_lines = None
        if model_path.is_file() and not args.refit:
            model = ObjectiveModel.load(model_path)
            print(f"model read from {model_path}")
        else:
            stage = build_stage("global", space, options, sampler, options.n_lines, options.samples_per_line,
                                options.search_points, paper=options.plan == "paper")
            model = stage.model
            model.save(model_path)
            fit_lines = list(zip(stage.line_designs, stage.line_values, strict=True))
            print(f"model fitted on {stage.n_samples} samples and saved to {model_path}")
        val = validate(model, space, sampler, options.validation_lines, options.validation_points, options.seed)
    figure = plot_validation(val.lines, out / "figures" / "validation.png", fit_lines, model)
    (out / "validation.json").write_text(json.dumps(val.summary(), indent=2))
    print(f"{val.n_points} held-out simulations on {len(val.lines)} lines: RMSE {val.rmse:.4f} N·m "
          f"({100 * val.rmse / val.t_min:.2f} % of T_min {val.t_min:.3f} N·m), {val.rmse_low:.4f} N·m where "
          f"T_RMS <= 2 T_min, max error {val.max_error:.4f} N·m")
    print(f"figure written to {figure}")
    return 0


def _cmd_feasible(args: argparse.Namespace) -> int:
    from mechopt.sim.fourbar.feasibility import check_feasibility
    from mechopt.surrogate import plan_lines

    from .definition import load_study
    from .design_space import from_u, to_u
    from .plots import plot_feasible_3d, plot_feasible_slices
    from .run import make_space

    study = load_study(args.study)
    options = _options(args, study)
    out = Path(args.out or f"{study.name}-study") / "figures"
    marks = {name: study.design(name) for name in study.designs}
    result = Path(args.out or f"{study.name}-study") / "result.json"
    if result.is_file():
        d = json.loads(result.read_text())["optimum"]["design_mm"]
        marks["optimum"] = np.array([d["oa"], d["ab"], d["bc"]])
    space = make_space(study, options)
    plan = plan_lines(to_u(space.box[:, 0]), to_u(space.box[:, 1]), space.feasible_u, n_lines=options.n_lines,
                      samples_per_line=options.samples_per_line, min_samples=min(options.min_samples,
                                                                                 options.samples_per_line),
                      seed=options.seed, sampleable=space.sampleable_u)
    lines = [from_u(plan.plan.points(i, np.arange(k0, k1 + 1))) for i, (k0, k1) in enumerate(plan.plan.k_ranges)]
    oa = sorted({float(study.region[0, 0]), float(np.mean(study.region[0])), float(study.region[0, 1])}
                | {float(m[0]) for m in marks.values() if study.region[0, 0] <= m[0] <= study.region[0, 1]})
    f1 = plot_feasible_slices(study, out / "feasible_slices.png", oa_values=oa[:5], marks=marks)
    f2 = plot_feasible_3d(study, out / "feasible_3d.png", lines=lines,
                          hull_points=from_u(plan.plan.segment_ends().reshape(-1, 3)), marks=marks)
    rng = np.random.default_rng(0)
    cloud = rng.uniform(study.region[:, 0], study.region[:, 1], size=(200_000, 3))
    share = check_feasibility(cloud, study.mechanism).feasible.mean()
    print(f"{100 * share:.1f} % of the region is feasible; the sampling lines' hull covers {plan.coverage:.0%} of it")
    for name, d in marks.items():
        print(check_feasibility(d, study.mechanism).message(0).replace("design", name, 1))
    print(f"figures written to {f1} and {f2}")
    return 0


def _int_list(text: str) -> list[int]:
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of integers") from None
    if not values or min(values) < 10:
        raise argparse.ArgumentTypeError(f"budgets {text!r}: expected integers >= 10")
    return values


def _cmd_compare(args: argparse.Namespace) -> int:
    from . import compare as cmp
    from .definition import load_study
    from .ground_truth import load_or_compute

    study = load_study(args.study)
    out = Path(args.out or f"{study.name}-study")
    if args.seeds < 1:
        raise MechoptError(f"--seeds {args.seeds}: expected at least 1")
    print(f"ground truth of {study.name} (analytic brute force, {args.truth_grid:g} mm grid; cached in {out})")
    truth = load_or_compute(study, out / f"ground_truth_{args.truth_grid:g}mm.json", args.truth_grid)
    print(f"  T_RMS {truth.fun:.4f} N·m at {np.round(truth.x, 3).tolist()} mm")
    methods = args.methods.split(",") if args.methods else None
    runs = cmp.compare(study, truth, args.budgets, args.seeds, args.engine, methods)
    md, fig = cmp.write(runs, truth, out, args.engine, args.seeds)
    print(md.read_text())
    print(f"table written to {md}, figure to {fig}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``mechopt`` with all its subcommands."""
    parser = argparse.ArgumentParser(
        prog="mechopt",
        description="Globally optimal mechanism dimensions from few motion simulations (lengths in mm).",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("simulate", help="simulate one design: feasibility with margins, T_RMS and T_max")
    p.add_argument("--oa", type=float, required=True, help="|OA|, crank length (mm)")
    p.add_argument("--ab", type=float, required=True, help="|AB|, coupler length (mm)")
    p.add_argument("--bc", type=float, required=True, help="|BC|, rocker length (mm)")
    _add_study(p)
    p.add_argument("--engine", choices=("pymunk", "analytic"), default="pymunk", help="simulation engine")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE", help="write the torque curve and the mechanism drawing to FILE (png)")
    p.set_defaults(func=_cmd_simulate)

    def run_options(p: argparse.ArgumentParser) -> None:
        p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
        p.add_argument("--workers", type=int, help="local worker processes (default: all cores)")
        p.add_argument("--scheduler", metavar="ADDR", help="Dask scheduler address tcp://HOST:PORT (dask extra)")
        p.add_argument("--store", metavar="FILE", help="SQLite sample store (default: DIR/samples.sqlite)")
        p.add_argument("--engine", choices=("pymunk", "analytic"), default="pymunk", help="simulation engine")
        p.add_argument("--plan", choices=("auto", "paper"),
                       help="line plan: automatic, or the paper's Δ, spacing, origin and 7 lines")
        p.add_argument("--lines-fit", type=int, help="lines of the global model (default: the study's; ventilator 21)")
        p.add_argument("--samples-per-line", type=int, help="target samples per line of the global model")
        p.add_argument("--search-points", type=int, help="grid points of the exhaustive search (default 10 million)")
        p.add_argument("--no-refine", action="store_true", help="report the model's candidate without local refinement")
        p.add_argument("--points-per-line", type=int, help="points per held-out line")
        p.add_argument("--no-progress", action="store_true", help="no progress bars")

    p = sub.add_parser("study", help="run a study: sample, fit, validate, search, confirm, report")
    p.add_argument("name", nargs="?", default="ventilator", help="study name or .toml path (default: ventilator)")
    run_options(p)
    p.add_argument("--lines", type=int, help="held-out validation lines (default 10)")
    p.add_argument("--truth-grid", type=float, default=1.0,
                   help="grid of the brute-force ground truth in mm (analytic engine; 0 skips it)")
    p.set_defaults(func=_cmd_study)

    p = sub.add_parser("validate", help="simulate held-out lines and compare them with the model")
    _add_study(p)
    run_options(p)
    p.add_argument("--lines", type=int, help="held-out lines (default 10)")
    p.add_argument("--refit", action="store_true", help="refit the model even if DIR/model.json exists")
    p.set_defaults(func=_cmd_validate)

    p = sub.add_parser("compare", help="the surrogate against the literature's optimizers at equal simulation budgets")
    _add_study(p)
    p.add_argument("--budgets", type=_int_list, default=[50, 100, 200, 618, 1870],
                   help="simulation budgets, comma separated (default 50,100,200,618,1870)")
    p.add_argument("--seeds", type=int, default=5, help="seeds per method and budget (default 5)")
    p.add_argument("--engine", choices=("pymunk", "analytic"), default="analytic",
                   help="simulator the methods call (default analytic, standing in for pymunk)")
    p.add_argument("--methods", help="comma-separated subset of the methods (default: all)")
    p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
    p.add_argument("--truth-grid", type=float, default=1.0, help="grid of the ground truth brute force (mm)")
    p.set_defaults(func=_cmd_compare)

    p = sub.add_parser("feasible", help="plot the feasible region: slices and a 3-D view with the sampling lines")
    _add_study(p)
    p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
    p.add_argument("--plan", choices=("auto", "paper"), help=argparse.SUPPRESS)
    p.set_defaults(func=_cmd_feasible)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``mechopt``; returns the exit status (see the module docstring)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except (MechoptError, SurrogateError) as exc:
        print(f"mechopt: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("mechopt: interrupted (results stored so far are kept)", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
