"""Commands on what mechopt ships: ``mechopt studies`` (the studies and test functions, one line each),
``mechopt methods`` (the optimizers ``--method`` accepts, with their options) and ``mechopt init`` (copy a study to
start one's own)."""

from __future__ import annotations

import argparse
import re
import shutil
import tomllib
from pathlib import Path

from mechopt.errors import InputError

__all__ = ["add_parsers", "method_lines", "run_init", "run_methods", "run_studies", "study_lines"]

def add_parsers(sub) -> None:
    """Add ``studies``, ``methods`` and ``init`` to the subcommands."""
    p = sub.add_parser("studies", help="list the packaged studies and test functions, one line each")
    p.set_defaults(func=run_studies)
    p = sub.add_parser("methods", help="list the optimizers `--method` accepts, with what each takes and its options")
    p.add_argument("name", nargs="?", metavar="METHOD", help="only this method")
    p.set_defaults(func=run_methods)
    p = sub.add_parser("init", help="copy a packaged study (its TOML and data) to start a study of your own")
    p.add_argument("name", help="the packaged study to copy (e.g. ventilator)")
    p.add_argument("--to", metavar="DIR", help="folder to copy it into (default: my-NAME; must be new or empty)")
    p.set_defaults(func=run_init)


def multi_objective_rows() -> list[tuple[str, str, str]]:
    """``(name, kind, description)`` of every test problem with several objectives."""
    from mechopt.studies.multi_objective_functions import MULTI_OBJECTIVE_SUITE

    rows = []
    for name, cls in sorted(MULTI_OBJECTIVE_SUITE.items()):
        p = cls()
        limits = f", {len(p.limits)} limits" if p.limits else ""
        rows.append((name, f"test problem, {p.dim} variables, {len(p.objective)} objectives{limits}", cls.summary()))
    return rows


def mixed_variable_rows() -> list[tuple[str, str, str]]:
    """``(name, kind, description)`` of every test problem with discrete variables."""
    from mechopt.studies.mixed_variable_functions import MIXED_SUITE

    rows = []
    for name, cls in sorted(MIXED_SUITE.items()):
        p = cls()
        kinds = ", ".join(f"{sum(v.kind == k for v in p.variables)} {k}" for k in ("continuous", "grid", "integer",
                                                                                   "catalogue")
                          if any(v.kind == k for v in p.variables))
        rows.append((name, f"test problem, {p.dim} variables ({kinds})", cls.summary()))
    return rows


def study_lines() -> list[str]:
    """``name  kind, d variables: description`` for every packaged study, then every test function.

    The study files are read as TOML only: building a study's problem can cost seconds (the ventilator's
    reconstruction), and a list needs none of it.
    """
    from mechopt.studies.benchmark_functions import SUITE
    from mechopt.studies.catalogue import STUDIES_DIR

    rows = []
    for path in sorted(STUDIES_DIR.glob("*/study.toml")):
        config = tomllib.loads(path.read_text())
        name = config.get("name", path.parent.name.replace("_", "-"))
        dim = len(config.get("variables", {}))
        rows.append((name, f"{config.get('kind', '?')}, {dim} variables", str(config.get("description", ""))))
    for name, cls in sorted(SUITE.items()):
        rows.append((name, f"test function, {cls().dim} variables", cls.summary()))
    rows += multi_objective_rows() + mixed_variable_rows()
    width = max(len(r[0]) for r in rows)
    return [f"{name:<{width}}  {what}: {text}" for name, what, text in rows]


def method_lines(name: str | None = None) -> list[str]:
    """Every method of :func:`mechopt.minimize` (or only ``name``): a line with its name and summary, then what it
    takes and its options with their defaults, indented (:func:`mechopt.optimize.methods.show_options`)."""
    from mechopt.optimize.methods import show_options

    return show_options(name).splitlines()


def run_studies(args: argparse.Namespace, rest: list[str]) -> int:
    """Print the catalogue."""
    print("\n".join(study_lines()))
    print("\nrun one with `mechopt study NAME`; compare optimizers on any of them with `mechopt compare --study NAME`")
    return 0


def run_methods(args: argparse.Namespace, rest: list[str]) -> int:
    """Print the methods."""
    print("\n".join(method_lines(args.name)))
    print("\nchoose one with `mechopt study NAME --method METHOD` or `mechopt.minimize(problem, method=...)`")
    return 0


def _copy_shared_data(folder: Path, to: Path) -> list[str]:
    """Copy the data files the study names in another packaged study (``"../ventilator/table.csv"``) beside the copy
    and name them there: a renamed copy (as the user is told to make) no longer finds the packaged study's folder."""
    toml = to / "study.toml"
    text = toml.read_text()
    copied = []
    for name in sorted(set(re.findall(r'"(\.\./[^"]+)"', text))):
        source = (folder / name).resolve()
        if source.is_file() and not (to / source.name).exists():
            shutil.copy2(source, to / source.name)
            copied.append(source.name)
        if (to / source.name).is_file():
            text = text.replace(f'"{name}"', f'"{source.name}"')
    toml.write_text(text)
    return copied


def run_init(args: argparse.Namespace, rest: list[str]) -> int:
    """Copy a packaged study's files into a new folder."""
    from mechopt.studies.benchmark_functions import SUITE
    from mechopt.studies.catalogue import STUDIES_DIR, packaged_studies

    files = packaged_studies()
    from mechopt.studies.mixed_variable_functions import MIXED_SUITE

    if args.name in SUITE or args.name in MIXED_SUITE:
        # A test function is a class, not a file: there is nothing to copy, and the list below must not name it.
        raise InputError(f"{args.name!r} is a test function (a Python class), not a study file to copy; expected one "
                         f"of {', '.join(files)}, or define a mechopt.DesignProblem (README: Define your own problem)")
    folder = STUDIES_DIR / args.name.replace("-", "_")
    if args.name.replace("_", "-") not in files or not (folder / "study.toml").is_file():
        raise InputError(f"unknown study {args.name!r}; expected one of {', '.join(files)}")
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
        copied += _copy_shared_data(folder, to)
    except OSError as exc:
        raise InputError(f"cannot copy the study into {to}: {exc.strerror or exc}") from None
    print(f"copied {', '.join(copied)} to {to}; edit {to / 'study.toml'} (give it a new name) and run "
          f"`mechopt study {to / 'study.toml'}`")
    return 0
