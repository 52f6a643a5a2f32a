"""``mechopt simulate``: one design's feasibility, with every constraint's margin, and its simulated outputs."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from mechopt.cli.arguments import Parser
from mechopt.cli.study_arguments import add_study_argument, load, study_name
from mechopt.errors import InfeasibleDesignError, InputError

__all__ = ["EXIT_INFEASIBLE", "add_parser", "feasibility_message"]

#: Exit status of ``simulate`` for an infeasible design (the answer is still printed).
EXIT_INFEASIBLE = 3


def add_parser(sub, engines: tuple[str, ...]) -> None:
    """Add ``simulate`` to the subcommands."""
    p = sub.add_parser("simulate", help="simulate one design: feasibility with margins and the outputs; the "
                       "variables are flags named after the study's (--oa 53 --ab 65 --bc 282 for a four-bar)")
    # The study as a first word is taken from the flags argparse leaves over: declared as a positional it would
    # swallow the value of the first variable's flag (--oa 53 is not known to the parser).
    add_study_argument(p, engines, word=False)
    p.usage = "mechopt simulate [STUDY] [--study STUDY] [--engine ENGINE] [--json] [--plot FILE] --VARIABLE VALUE ..."
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE", help="write the mechanism's figure of the design to FILE (png)")
    p.set_defaults(func=run, extra=True)


def _design(problem, args: argparse.Namespace, rest: list[str]) -> np.ndarray:
    """The design given as one flag per variable (``--oa 53``), each a finite number."""
    p = Parser(prog=f"mechopt simulate {study_name(args)}")
    for v in problem.variables:
        p.add_argument(f"--{v.name}", type=float, required=True, help=f"{v.label or v.name} ({v.unit})")
    values = p.parse_args(rest)
    x = np.array([getattr(values, v.name) for v in problem.variables], dtype=float)
    for v, value in zip(problem.variables, x, strict=True):
        if not math.isfinite(value):
            raise InputError(f"--{v.name} = {value}: expected a finite number ({v.unit})")
    return x


def run(args: argparse.Namespace, rest: list[str]) -> int:
    """Simulate the design; 0 if feasible, :data:`EXIT_INFEASIBLE` if not."""
    if rest and not rest[0].startswith("-"):
        args.name, rest = rest[0], rest[1:]
    problem = load(args).problem
    x = _design(problem, args, rest)
    if args.plot:
        from mechopt.sim.figure_file import figure_path

        figure_path(args.plot)
    margins = dict(zip(problem.constraints, problem.constraint_margins(x[None, :])[0].tolist(), strict=True))
    feasible = bool(problem.feasible(x)[0])
    message = feasibility_message(problem, x, margins, feasible)
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
        files = list(problem.figures({"design": x}, Path(args.plot).parent).values())
        if files:
            Path(files[0]).replace(args.plot)
    if args.json:
        print(json.dumps({"design": problem.design_dict(x), "feasible": feasible, "simulated": True,
                          "margins": margins, "outputs": outputs, "engine": problem.settings().get("engine")}))
    else:
        print(message)
        engine = problem.settings().get("engine")
        values = ", ".join(f"{k} = {v:.6g}" for k, v in outputs.items()
                           if isinstance(v, float) and k in problem.outputs)
        print(f"{f'engine {engine}' if engine else 'simulated'}: {values}")
        if args.plot:
            print(f"figure written to {args.plot}")
    return 0 if feasible else EXIT_INFEASIBLE


def feasibility_message(problem, x: np.ndarray, margins: dict, feasible: bool) -> str:
    """One line: the design, and either its margins or the constraints it violates and by how much."""
    head = f"design {problem.describe(x)}"
    if not problem.in_box(x)[0]:
        head += " (outside the study's region)"
    failed = [f"{k} violated by {-v:.4g}" for k, v in margins.items() if not v >= 0]
    if feasible:
        if not margins:
            return f"{head}: feasible (the problem declares no constraints)"
        return f"{head}: feasible (margins: " + ", ".join(f"{k} {v:.4g}" for k, v in margins.items()) + ")"
    return f"{head}: infeasible — " + ("; ".join(failed) if failed else "outside the region")
