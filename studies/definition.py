"""Study definitions: a TOML file (plus its data files) that says which mechanism to optimise and where.

A study is loaded by name (a folder of this package holding ``study.toml``, e.g. ``ventilator``) or by the path of a
TOML file.  Every key is checked: a missing, misspelt or ill-typed key is a one-line :class:`StudyError` naming it.
Lengths in mm, angles in degrees, times in s in the file; converted to rad here.
"""

from __future__ import annotations

import functools
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mechopt.errors import MechoptError, StudyError
from mechopt.sim.fourbar.kinematics import BRANCH_ADD, BRANCH_SUBTRACT
from mechopt.sim.fourbar.load import RockerLoad
from mechopt.sim.fourbar.mechanism import FourBar
from mechopt.sim.fourbar.motion import LAW_CODES, MotionLaw

from .ventilator.reconstruction import Reconstruction, read_motor_table, reconstruct

STUDIES_DIR = Path(__file__).resolve().parent

_SECTIONS = {"name", "description", "mechanism", "reconstruction", "motion", "region", "designs", "load",
             "surrogate", "simulation", "validation", "compare"}
_MECHANISM_KEYS = {"kind", "ground", "assembly_branch", "coupler_mass_kg", "toggle_margin_deg", "pivot_c_mm",
                   "j0_kgm2", "i_r_kgm2"}
_RECONSTRUCTION_KEYS = {"table", "original_mm", "theta_start_deg", "theta_end_deg", "n_starts", "seed"}
_MOTION_KEYS = {"law", "stroke_time_s", "psi_start_deg", "psi_end_deg"}
_REGION_KEYS = {"oa_mm", "ab_mm", "bc_mm"}
_LOAD_KEYS = {"rocker_Nm", "table"}
_BRANCHES = {"theta1": BRANCH_SUBTRACT, "theta2": BRANCH_ADD}


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
    mechanism : FourBar
        The fixed part of the mechanism (pivot, inertias, load, motion, branch, toggle margin).
    region : (3, 2) ndarray
        Bounds of |OA|, |AB|, |BC| (mm), the region of interest.
    designs : dict
        Reference designs by name: ``{"oa", "ab", "bc"}`` in mm plus optional paper figures.
    reconstruction : Reconstruction or None
        How the mechanism was recovered from data, when it was.
    config : dict
        The raw TOML, for the sections that later stages read (``surrogate``, ``simulation``...).
    """

    name: str
    path: Path
    description: str
    mechanism: FourBar
    region: np.ndarray
    designs: dict[str, dict[str, float]] = field(default_factory=dict)
    reconstruction: Reconstruction | None = None
    config: dict[str, Any] = field(default_factory=dict)

    def design(self, name: str) -> np.ndarray:
        """Reference design ``name`` as (|OA|, |AB|, |BC|) in mm."""
        if name not in self.designs:
            raise StudyError(f"study {self.name!r} has no design {name!r}; it has {sorted(self.designs)}")
        d = self.designs[name]
        return np.array([d["oa"], d["ab"], d["bc"]], dtype=float)

    def section(self, name: str) -> dict[str, Any]:
        """A raw TOML section (empty dict when absent)."""
        value = self.config.get(name, {})
        return value if isinstance(value, dict) else {}


def available_studies() -> list[str]:
    """Names of the studies shipped with mechopt."""
    return sorted(p.parent.name for p in STUDIES_DIR.glob("*/study.toml"))


def _resolve(name_or_path: str | Path) -> Path:
    candidate = Path(name_or_path)
    if candidate.suffix == ".toml":
        if not candidate.is_file():
            raise StudyError(f"study file {candidate} not found")
        return candidate.resolve()
    shipped = STUDIES_DIR / str(name_or_path) / "study.toml"
    if shipped.is_file():
        return shipped
    raise StudyError(
        f"unknown study {str(name_or_path)!r}: expected one of {available_studies()} or the path of a .toml file"
    )


def load_study(name_or_path: str | Path) -> Study:
    """Load and check a study by name or TOML path.

    Parameters
    ----------
    name_or_path : str or Path
        A shipped study's name (``"ventilator"``) or a ``.toml`` path.

    Returns
    -------
    Study

    Raises
    ------
    StudyError
        Unknown study, malformed TOML, or a missing / unknown / ill-typed key (the message names it).
    """
    path = _resolve(name_or_path)
    return _load_cached(str(path), path.stat().st_mtime_ns)


@functools.lru_cache(maxsize=8)
def _load_cached(path_str: str, _mtime: int) -> Study:
    path = Path(path_str)
    try:
        config = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"malformed TOML in {path.name}: {exc}") from None
    try:
        return _build(path, config)
    except StudyError:
        raise
    except MechoptError as exc:
        raise StudyError(f"{path.name}: {exc}") from None


def _section(config: dict, key: str, allowed: set[str], where: str) -> dict:
    value = config.get(key)
    if not isinstance(value, dict):
        raise StudyError(f"{where}: missing section [{key}]")
    unknown = set(value) - allowed
    if unknown:
        raise StudyError(f"{where}: unknown key {key}.{sorted(unknown)[0]}; expected one of {sorted(allowed)}")
    return value


def _number(section: dict, key: str, where: str, default: float | None = None, positive: bool = False) -> float:
    if key not in section:
        if default is None:
            raise StudyError(f"{where}: missing key {key}")
        return default
    value = section[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value):
        raise StudyError(f"{where}: key {key} = {value!r} must be a finite number")
    if positive and value <= 0:
        raise StudyError(f"{where}: key {key} = {value!r} must be > 0")
    return float(value)


def _pair(section: dict, key: str, where: str) -> tuple[float, float]:
    if key not in section:
        raise StudyError(f"{where}: missing key {key}")
    value = section[key]
    if (
        not isinstance(value, list) or len(value) != 2
        or not all(isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v) for v in value)
    ):
        raise StudyError(f"{where}: key {key} = {value!r} must be a list of two finite numbers")
    return float(value[0]), float(value[1])


def _design_table(value: Any, key: str, where: str) -> dict[str, float]:
    if not isinstance(value, dict):
        raise StudyError(f"{where}: key {key} must be a table with oa, ab, bc in mm")
    out = {}
    for k in value:
        out[k] = _number(value, k, f"{where} [{key}]")
    for k in ("oa", "ab", "bc"):
        if k not in out:
            raise StudyError(f"{where}: key {key}.{k} missing")
        if out[k] <= 0:
            raise StudyError(f"{where}: key {key}.{k} = {out[k]!r} must be a length > 0 mm")
    return out


def _build(path: Path, config: dict) -> Study:
    where = path.name
    unknown = set(config) - _SECTIONS
    if unknown:
        raise StudyError(f"{where}: unknown key {sorted(unknown)[0]}; expected one of {sorted(_SECTIONS)}")
    name = config.get("name", path.parent.name)
    if not isinstance(name, str) or not name:
        raise StudyError(f"{where}: key name must be a non-empty string")
    mech = _section(config, "mechanism", _MECHANISM_KEYS, where)
    if mech.get("kind", "four-bar") != "four-bar":
        raise StudyError(f"{where}: key mechanism.kind = {mech.get('kind')!r}; only 'four-bar' is supported")
    branch_name = mech.get("assembly_branch", "theta1")
    if branch_name not in _BRANCHES:
        raise StudyError(f"{where}: key mechanism.assembly_branch = {branch_name!r}; expected theta1 or theta2")
    motion_cfg = _section(config, "motion", _MOTION_KEYS, where)
    law = motion_cfg.get("law", "quintic")
    if law not in LAW_CODES:
        raise StudyError(f"{where}: key motion.law = {law!r}; expected one of {sorted(LAW_CODES)}")
    stroke_time = _number(motion_cfg, "stroke_time_s", where + " [motion]", positive=True)

    ground = mech.get("ground", "explicit")
    reconstruction = None
    if ground == "reconstruction":
        rec_cfg = _section(config, "reconstruction", _RECONSTRUCTION_KEYS, where)
        table_name = rec_cfg.get("table")
        if not isinstance(table_name, str):
            raise StudyError(f"{where}: missing key reconstruction.table")
        original = _design_table(rec_cfg.get("original_mm"), "reconstruction.original_mm", where)
        reconstruction = _reconstruct_cached(
            str(path.parent / table_name),
            (original["oa"], original["ab"], original["bc"]),
            _number(rec_cfg, "theta_start_deg", where + " [reconstruction]"),
            _number(rec_cfg, "theta_end_deg", where + " [reconstruction]"),
            int(_number(rec_cfg, "n_starts", where + " [reconstruction]", 400, positive=True)),
            int(_number(rec_cfg, "seed", where + " [reconstruction]", 0)),
        )
        pivot = reconstruction.pivot_c
        j0, i_r = reconstruction.j0, reconstruction.i_r
        psi_start, psi_end = reconstruction.psi_start, reconstruction.psi_end
        load = reconstruction.load
        if _BRANCHES[branch_name] != reconstruction.inverse_branch:
            raise StudyError(f"{where}: mechanism.assembly_branch = {branch_name!r} does not assemble the original "
                             "as the table does")
    elif ground == "explicit":
        pivot = _pair(mech, "pivot_c_mm", where + " [mechanism]")
        j0 = _number(mech, "j0_kgm2", where + " [mechanism]")
        i_r = _number(mech, "i_r_kgm2", where + " [mechanism]")
        psi_start = np.radians(_number(motion_cfg, "psi_start_deg", where + " [motion]"))
        psi_end = np.radians(_number(motion_cfg, "psi_end_deg", where + " [motion]"))
        load = _explicit_load(config, path, where)
    else:
        raise StudyError(f"{where}: key mechanism.ground = {ground!r}; expected 'reconstruction' or 'explicit'")

    motion = MotionLaw(psi_start, psi_end, stroke_time, law)
    mechanism = FourBar(
        pivot_c=pivot, j0=j0, i_r=i_r, motion=motion, load=load,
        coupler_mass=_number(mech, "coupler_mass_kg", where + " [mechanism]", 0.0),
        branch=_BRANCHES[branch_name],
        toggle_margin_deg=_number(mech, "toggle_margin_deg", where + " [mechanism]", 15.0),
    )
    region_cfg = _section(config, "region", _REGION_KEYS, where)
    region = np.array([_pair(region_cfg, k, where + " [region]") for k in ("oa_mm", "ab_mm", "bc_mm")])
    for k, (lo, hi) in zip(("oa_mm", "ab_mm", "bc_mm"), region, strict=True):
        if not 0 < lo < hi:
            raise StudyError(f"{where}: key region.{k} = [{lo}, {hi}] must satisfy 0 < low < high")
    designs_cfg = config.get("designs", {})
    if not isinstance(designs_cfg, dict):
        raise StudyError(f"{where}: key designs must be a table of named designs")
    designs = {k: _design_table(v, f"designs.{k}", where) for k, v in designs_cfg.items()}
    return Study(
        name=name, path=path, description=str(config.get("description", "")), mechanism=mechanism,
        region=region, designs=designs, reconstruction=reconstruction, config=config,
    )


def _explicit_load(config: dict, path: Path, where: str) -> RockerLoad:
    load_cfg = config.get("load", {"rocker_Nm": 0.0})
    if not isinstance(load_cfg, dict):
        raise StudyError(f"{where}: key load must be a table")
    unknown = set(load_cfg) - _LOAD_KEYS
    if unknown:
        raise StudyError(f"{where}: unknown key load.{sorted(unknown)[0]}; expected one of {sorted(_LOAD_KEYS)}")
    if "table" in load_cfg:
        table_path = path.parent / str(load_cfg["table"])
        if not table_path.is_file():
            raise StudyError(f"{where}: key load.table: file {table_path.name} not found")
        try:
            data = np.loadtxt(table_path, delimiter=",", skiprows=1, ndmin=2)
        except ValueError as exc:
            raise StudyError(f"{where}: load table {table_path.name}: {exc}") from None
        return RockerLoad.from_table(np.radians(data[:, 0]), data[:, 1])
    return RockerLoad.constant(_number(load_cfg, "rocker_Nm", where + " [load]", 0.0))


@functools.lru_cache(maxsize=4)
def _reconstruct_cached(table_path, original, theta_start_deg, theta_end_deg, n_starts, seed):
    table = read_motor_table(Path(table_path))
    return reconstruct(table, original, np.radians(theta_start_deg), np.radians(theta_end_deg), n_starts, seed)
