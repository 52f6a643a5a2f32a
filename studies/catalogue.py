"""Study definitions: a TOML file (plus its data files) that names a mechanism kind, its settings and its region.

A study is loaded by name (a folder of this package holding ``study.toml``, e.g. ``ventilator``) or by the path of a
TOML file.  The engine reads the sections every study has (``name``, ``description``, ``kind``, ``[variables]``,
``[designs.*]``, ``[surrogate]``, ``[paper]``, ``[compare]``); the mechanism plug-in registered for ``kind`` reads
the rest and returns the :class:`~mechopt.optimize.problem.DesignProblem`.  Every key is checked: a missing, misspelt
or ill-typed key is a one-line :class:`~mechopt.errors.StudyError` naming it.
"""

from __future__ import annotations

import functools
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import MechoptError, StudyError
from mechopt.optimize.problem import DesignProblem
from mechopt.studies.registry import mechanism_factory
from mechopt.studies.study_file import PACKAGED_STUDIES, StudyFile

__all__ = ["STUDIES_DIR", "Study", "available_studies", "load_study", "packaged_studies"]

STUDIES_DIR = PACKAGED_STUDIES

#: The overrides :func:`load_study` passes to a mechanism plug-in (the command line's ``--engine``).
OVERRIDES = ("engine",)
#: Top-level keys the engine reads (a plug-in reads its own sections through :meth:`StudyFile.table`, which
#: records them); any other key of a study file is refused.
ENGINE_SECTIONS = {"name", "description", "kind", "method", "variables", "designs", "surrogate", "paper", "compare",
                   "validation", "simulator", "tolerances"}


@dataclass(frozen=True)
class Study:
    """A loaded study.

    Attributes
    ----------
    name : str
        Study name.
    path : Path
        The TOML file.
    description : str
        One line for reports.
    kind : str
        The mechanism plug-in (``"four-bar"``...).
    problem : DesignProblem
        The design problem built by the plug-in.
    designs : dict
        Reference designs by name: ``{variable: value, "paper_...": figure}``.
    paper : dict
        The paper's figures the report compares with (``[paper]``).
    file : StudyFile
        The parsed file, for the sections later stages read (``surrogate``, ``compare``...).
    method : str
        The study's own choice of method (its key ``method``; ``--method`` overrides it); empty: the default of
        :func:`mechopt.minimize`.
    tolerances : StudyTolerances or None
        Its ``[tolerances]`` table (:mod:`mechopt.studies.tolerances_section`).
    """

    name: str
    path: Path
    description: str
    kind: str
    problem: DesignProblem
    designs: dict[str, dict[str, float]] = field(default_factory=dict)
    paper: dict[str, Any] = field(default_factory=dict)
    file: StudyFile | None = None
    method: str = ""
    tolerances: Any = None

    def design(self, name: str) -> np.ndarray:
        """Reference design ``name`` as an array in the problem's variable order."""
        if name not in self.designs:
            raise StudyError(f"study {self.name!r} has no design {name!r}; it has {sorted(self.designs)}")
        return np.array([self.designs[name][v] for v in self.problem.names], dtype=float)

    def reference_designs(self) -> dict[str, np.ndarray]:
        """Every reference design, name -> array."""
        return {name: self.design(name) for name in self.designs}

    def section(self, name: str) -> dict[str, Any]:
        """A raw TOML section (empty dict when absent)."""
        value = self.file.config.get(name, {}) if self.file else {}
        return value if isinstance(value, dict) else {}

    @property
    def config(self) -> dict[str, Any]:
        """The whole parsed TOML."""
        return self.file.config if self.file else {}


def packaged_studies() -> list[str]:
    """Names of the study files shipped with mechopt (what ``mechopt init`` can copy)."""
    return sorted(p.parent.name.replace("_", "-") for p in STUDIES_DIR.glob("*/study.toml"))


def available_studies() -> list[str]:
    """Names of the studies shipped with mechopt, then of the test functions and test problems (classes, no file)."""
    return packaged_studies() + [name for suite in _test_suites() for name in sorted(suite[1])]


def _test_suites() -> list[tuple[str, dict[str, Any], Path]]:
    """``(kind, {name: problem class}, module file)`` of each registry of test problems."""
    from mechopt.studies import benchmark_functions, mixed_variable_functions, multi_objective_functions

    return [("test-function", benchmark_functions.SUITE, Path(benchmark_functions.__file__)),
            ("test-problem", multi_objective_functions.MULTI_OBJECTIVE_SUITE, Path(multi_objective_functions.__file__)),
            ("test-function", mixed_variable_functions.MIXED_SUITE, Path(mixed_variable_functions.__file__))]


def _suite_study(name: str) -> Study | None:
    """A test function or test problem of a suite as a study (no file: its problem is a class)."""
    for kind, suite, path in _test_suites():
        cls = suite.get(name)
        if cls is not None:
            return Study(name=name, path=path, description=cls.summary(), kind=kind, problem=cls())
    return None


def _resolve(name_or_path: str | Path) -> Path:
    candidate = Path(name_or_path)
    if candidate.suffix == ".toml":
        if not candidate.is_file():
            raise StudyError(f"study file {candidate} not found")
        return candidate.resolve()
    shipped = STUDIES_DIR / str(name_or_path) / "study.toml"
    if shipped.is_file():
        return shipped
    folders = {p.parent.name.replace("_", "-"): p for p in STUDIES_DIR.glob("*/study.toml")}
    if str(name_or_path) in folders:
        return folders[str(name_or_path)]
    raise StudyError(
        f"unknown study {str(name_or_path)!r}: expected one of {available_studies()} or the path of a .toml file"
    )


def load_study(name_or_path: str | Path, options: dict[str, Any] | None = None) -> Study:
    """Load and check a study by name or TOML path.

    Parameters
    ----------
    name_or_path : str or Path
        A shipped study's name (``"ventilator"``) or a ``.toml`` path.
    options : dict, optional
        Overrides passed to the mechanism plug-in (``{"engine": "analytic"}``; keys: :data:`OVERRIDES`).

    Returns
    -------
    Study

    Raises
    ------
    StudyError
        Unknown study, malformed TOML, or a missing / unknown / ill-typed key (the message names it).
    """
    _check_overrides(options)
    suite = _suite_study(str(name_or_path))
    if suite is not None:
        return suite
    path = _resolve(name_or_path)
    items = tuple(sorted((k, v) for k, v in (options or {}).items() if v is not None))
    return _load_cached(str(path), path.stat().st_mtime_ns, items)


def _check_overrides(options: Any) -> None:
    """Refuse overrides that are not a mapping of :data:`OVERRIDES` (a mistyped key would be ignored)."""
    if options is None:
        return
    if not isinstance(options, Mapping):
        raise StudyError(f"options = {options!r}: expected a mapping of overrides such as {{'engine': 'analytic'}}")
    for key in options:
        if key not in OVERRIDES:
            raise StudyError(f"unknown override {key!r}; expected one of {', '.join(OVERRIDES)}")


@functools.lru_cache(maxsize=16)
def _load_cached(path_str: str, _mtime: int, options: tuple) -> Study:
    path = Path(path_str)
    try:
        config = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"malformed TOML in {path.name}: {exc}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise StudyError(f"cannot read study file {path}: {exc}") from None
    name = config.get("name", path.parent.name)
    if not isinstance(name, str) or not name:
        raise StudyError(f"{path.name}: key name must be a non-empty string")
    packaged = name if (STUDIES_DIR / name / "study.toml").is_file() else None
    if packaged is None and (STUDIES_DIR / name.replace("-", "_") / "study.toml").is_file():
        packaged = name.replace("-", "_")
    file = StudyFile(path, config, packaged)
    kind = config.get("kind")
    if not isinstance(kind, str):
        raise StudyError(f"{path.name}: missing key kind (the mechanism plug-in, e.g. kind = \"four-bar\")")
    try:
        problem = mechanism_factory(kind)(file, dict(options))
        if "simulator" in config:
            # A user's simulator (a command or a Python function) replaces only the plug-in's evaluator.
            from mechopt.studies.kinds.simulator_section import with_simulator

            problem = with_simulator(file, problem)
        problem.check()
        from mechopt.studies.trade_off_section import with_trade_off

        problem = with_trade_off(file, problem)
    except StudyError:
        raise
    except MechoptError as exc:
        raise StudyError(f"{path.name}: {exc}") from None
    designs = _designs(file, problem)
    paper = file.table("paper", required=False)
    from mechopt.studies.tolerances_section import read_tolerances

    tolerances = read_tolerances(file, problem)
    unread = sorted(set(config) - ENGINE_SECTIONS - file.read)
    if unread:
        raise StudyError(f"{path.name}: unknown key {unread[0]}; kind {kind!r} reads "
                         f"{', '.join(sorted(ENGINE_SECTIONS | file.read))}")
    method = config.get("method", "")
    if not isinstance(method, str):
        raise StudyError(f"{path.name}: key method must be a method's name (`mechopt methods`), got {method!r}")
    return Study(name=name, path=path, description=str(config.get("description", "")), kind=kind, problem=problem,
                 designs=designs, paper=dict(paper), file=file, method=method,
                 tolerances=tolerances)


def _designs(file: StudyFile, problem: DesignProblem) -> dict[str, dict[str, float]]:
    table = file.table("designs", required=False)
    out = {}
    for name, value in table.items():
        if not isinstance(value, dict):
            raise StudyError(f"{file.where}: key designs.{name} must be a table of the variables {list(problem.names)}")
        entry = {}
        for key in value:
            if key not in problem.names and not key.startswith("paper_"):
                raise StudyError(f"{file.where}: unknown key designs.{name}.{key}; expected the variables "
                                 f"{list(problem.names)} or paper_* figures")
            entry[key] = file.number(value, key, f"designs.{name}")
        missing = [v for v in problem.names if v not in entry]
        if missing:
            raise StudyError(f"{file.where}: key designs.{name}.{missing[0]} missing")
        out[name] = entry
    return out
