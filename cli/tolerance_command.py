"""``mechopt tolerance``: a design's scatter under manufacturing tolerances (each margin's probability of violation,
the objective's mean and quantiles, a few confirming simulations), optionally the objective's Sobol indices."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mechopt.cli.arguments import count
from mechopt.cli.study_arguments import add_study_argument, load
from mechopt.errors import InputError

__all__ = ["add_parser", "run"]


def add_parser(sub, engines: tuple[str, ...]) -> None:
    """Add ``tolerance`` to the subcommands."""
    p = sub.add_parser("tolerance", help="tolerance analysis of a design: probability of violating each margin, "
                       "the objective's mean and 5/50/95 %% quantiles; --sobol for the Sobol indices")
    add_study_argument(p, engines)
    p.add_argument("--design", required=True, metavar="NAME=VALUE,...",
                   help="the nominal design, every variable in its unit (oa=30,ab=70.56,bc=254.59)")
    p.add_argument("--tol", type=float, metavar="T", help="± tolerance of every variable, in its unit")
    p.add_argument("--tol-of", metavar="NAME=T,...", help="± tolerance per variable (overrides --tol for those)")
    p.add_argument("--distribution", choices=("uniform", "normal"), default="uniform",
                   help="uniform on ±T (default) or normal with T = 3σ")
    p.add_argument("--store", metavar="FILE", help="a run's sample store: its designs build the objective's model")
    p.add_argument("--simulations", type=count, default=10,
                   help="most new simulations (local designs when the store has too few, then the quantiles)")
    p.add_argument("--sobol", action="store_true", help="also the Sobol indices of the objective")
    p.add_argument("--region", metavar="NAME=LO:HI,...", help="box of the Sobol indices (default: feasible extent)")
    p.add_argument("--out", metavar="DIR", help="write tolerance.json and the figures there")
    p.set_defaults(func=run)


def _pairs(text: str, what: str) -> dict[str, str]:
    """``a=1,b=2`` -> {"a": "1", "b": "2"}."""
    out = {}
    for item in filter(None, (s.strip() for s in text.split(","))):
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise InputError(f"{what} {item!r}: expected NAME=VALUE pairs separated by commas")
        out[name.strip()] = value.strip()
    return out


def _number(text: str, what: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise InputError(f"{what} = {text!r}: expected a number") from None


def _design(problem, text: str) -> list[float]:
    values = _pairs(text, "--design")
    unknown = sorted(set(values) - set(problem.names))
    if unknown:
        raise InputError(f"--design: unknown variable {unknown[0]!r}; expected {list(problem.names)}")
    missing = [n for n in problem.names if n not in values]
    if missing:
        raise InputError(f"--design: {missing[0]} missing; expected every variable of {list(problem.names)}")
    return [_number(values[n], f"--design {n}") for n in problem.names]


def _tolerances(problem, args: argparse.Namespace):
    from mechopt.optimize.analysis.scatter import Tolerances

    values = dict.fromkeys(problem.names, args.tol) if args.tol is not None else {}
    if args.tol_of:
        values.update({k: _number(v, f"--tol-of {k}") for k, v in _pairs(args.tol_of, "--tol-of").items()})
    if not values:
        raise InputError("no tolerance given: expected --tol T or --tol-of NAME=T,...")
    return Tolerances(values, distribution=args.distribution)


def _region(text: str | None):
    if not text:
        return None
    out = {}
    for name, value in _pairs(text, "--region").items():
        lo, sep, hi = value.partition(":")
        if not sep:
            raise InputError(f"--region {name}={value!r}: expected LO:HI")
        out[name] = (_number(lo, f"--region {name}"), _number(hi, f"--region {name}"))
    return out


def run(args: argparse.Namespace, _rest: list[str]) -> int:
    """Analyse the design; print the lines, and write JSON and figures with ``--out``."""
    from mechopt.optimize.analysis import sensitivity, tolerance

    problem = load(args).problem
    x = _design(problem, args.design)
    tol = _tolerances(problem, args)
    region = _region(args.region)
    out = Path(args.out) if args.out else None
    result = tolerance(problem, x, tol, store=args.store, simulations=args.simulations)
    print("\n".join(result.lines(problem)))
    summary = {"tolerance": result.to_dict(problem)}
    sens = None
    if args.sobol:
        budget = max(args.simulations, 10 * problem.dim)
        sens = sensitivity(problem, store=args.store, region=region, simulations=budget)
        print("\n".join(sens.lines()))
        summary["sensitivity"] = sens.to_dict()
    if out is not None:
        from mechopt.report.tolerance_figures import plot_sobol, plot_tolerance

        out.mkdir(parents=True, exist_ok=True)
        (out / "tolerance.json").write_text(json.dumps(summary, indent=2))
        files = [plot_tolerance(problem, result, out / "tolerance.png")]
        if sens is not None:
            files.append(plot_sobol(sens, out / "sobol.png", problem.objective))
        print(f"written: {out / 'tolerance.json'}, " + ", ".join(map(str, files)))
    return 0
