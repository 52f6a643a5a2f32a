"""The ``mechopt`` command line.

Exit status: 0 success; 1 a user error (bad input, unknown study, malformed TOML), printed as one line on stderr;
3 for ``simulate`` when the design is infeasible (the answer is still printed: which constraint fails, by how much).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from sim.errors import InfeasibleDesignError, MechoptError

EXIT_ERROR = 1
EXIT_INFEASIBLE = 3


def _add_study(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--study", default="ventilator", help="study name or path of a study .toml (default: ventilator)"
    )


def _cmd_simulate(args: argparse.Namespace) -> int:
    from sim.feasibility import check_feasibility
    from sim.kinematics import check_design
    from sim.simulate import simulate

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
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``mechopt``; returns the exit status (see the module docstring)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except MechoptError as exc:
        print(f"mechopt: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("mechopt: interrupted (results stored so far are kept)", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
