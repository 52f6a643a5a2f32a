"""What the commands that run a study share: loading it, and the options of a run (``--out``, ``--workers``,
``--budget``, ``--method``...), checked as :func:`mechopt.minimize` checks its own arguments."""

from __future__ import annotations

import argparse
from typing import Any

from mechopt.cli.arguments import count, positive_int
from mechopt.errors import InputError

__all__ = ["add_method_option", "add_run_options", "add_study_argument", "load", "overrides", "study_name"]

#: The study a command runs when none is named: the main job.
DEFAULT_STUDY = "ventilator"


def study_name(args: argparse.Namespace) -> str:
    """The study named on the command line, first word or ``--study`` (both is an error unless they agree)."""
    word, flag = getattr(args, "name", None), getattr(args, "study", None)
    for given in (word, flag):
        if given is not None and not given.strip(", "):
            # An empty name (a shell variable never set) must not quietly run the default study.
            raise InputError(f"study {given!r} names no study; expected a name such as {DEFAULT_STUDY} (`mechopt "
                             "studies` lists them) or the path of a study .toml")
    if word and flag and word != flag:
        raise InputError(f"study named twice: {word!r} and --study {flag!r}; expected one of them")
    return word or flag or DEFAULT_STUDY


def load(args: argparse.Namespace):
    """The study named on the command line, with the ``--engine`` override."""
    from mechopt.studies.catalogue import load_study

    return load_study(study_name(args), {"engine": getattr(args, "engine", None)})


def add_study_argument(p: argparse.ArgumentParser, engines: tuple[str, ...], word: bool = True) -> None:
    """The study, as the first word (``word``) or ``--study``, and ``--engine``."""
    what = f"study name or path of a study .toml (default {DEFAULT_STUDY}; `mechopt studies` lists them)"
    if word:
        p.add_argument("name", nargs="?", metavar="STUDY", help=what)
    p.add_argument("--study", help=what if not word else "the same, as a flag")
    p.add_argument("--engine", choices=engines, help="simulation engine (default: the study's)")


def add_run_options(p: argparse.ArgumentParser) -> None:
    """The options of a run that samples designs: output, workers, store, line plan, budget, seed."""
    p.add_argument("--out", metavar="DIR", help="output folder (default: STUDY-study)")
    p.add_argument("--workers", type=positive_int, help="local worker processes (default: all cores)")
    p.add_argument("--scheduler", metavar="ADDR", help="Dask scheduler address tcp://HOST:PORT (dask extra)")
    p.add_argument("--store", metavar="FILE", help="SQLite sample store (default: DIR/samples.sqlite)")
    p.add_argument("--plan", choices=("auto", "paper"),
                   help="line plan: automatic, or the paper's Δ, spacing, origin and 7 lines")
    p.add_argument("--lines-fit", type=positive_int, help="lines of the global model (ventilator: 21)")
    p.add_argument("--samples-per-line", type=positive_int, help="target samples per line of the global model")
    p.add_argument("--search-points", type=positive_int, help="grid points of the exhaustive search")
    # Checked with the API's own rule (mechopt.optimize.arguments.check_budget) once the study is known.
    p.add_argument("--budget", type=int, help="most simulations to optimise (default: the study's)")
    p.add_argument("--seed", type=count, help="seed of the planner and the validation lines")
    p.add_argument("--no-refine", action="store_true", help="report the model's candidate without local refinement")
    p.add_argument("--points-per-line", type=positive_int, help="points per held-out line")
    p.add_argument("--retry-failed", action="store_true", help="simulate again designs whose simulation failed")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--stop-after-failures", type=count, default=5, metavar="K",
                   help="stop when the run's first K simulations all fail (default 5; 0: never)")


def add_method_option(p: argparse.ArgumentParser) -> None:
    """``--method``: any name :func:`mechopt.minimize` accepts."""
    # The names are checked after parsing (mechopt.optimize.arguments.check_method): listing them here would import
    # every baseline library at each call of the command line.
    p.add_argument("--method", default=None, metavar="NAME",
                   help="the optimizer: the study's own (its key `method`), else mechopt's default; sparse (the line "
                   "model of paper 002), sparse-global, auto, or a baseline (`mechopt methods` lists them)")


def overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The command line's overrides of a study's ``[surrogate]`` section (None: the study's own)."""
    return {
        "plan": getattr(args, "plan", None),
        "n_lines": getattr(args, "lines_fit", None),
        "samples_per_line": getattr(args, "samples_per_line", None),
        "search_points": getattr(args, "search_points", None),
        "refine": False if getattr(args, "no_refine", False) else None,
        "validation_lines": getattr(args, "lines", None),
        "validation_points": getattr(args, "points_per_line", None),
        "validation_budget": getattr(args, "validation", None),
        "budget": getattr(args, "budget", None),
        "seed": getattr(args, "seed", None),
    }
