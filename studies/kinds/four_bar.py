"""A four-bar study file read into a :class:`~mechopt.sim.four_bar.problem.FourBarProblem`.

Sections read here: ``[mechanism]`` (kind-specific keys), ``[reconstruction]`` (when the ground pivot and inertias
are fitted to a motor-side table), ``[motion]``, ``[load]`` and ``[sampling]``.  Lengths in mm, angles in degrees,
times in s in the file; converted to rad here.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import MechoptError, StudyError
from mechopt.sim.four_bar.kinematics import BRANCH_ADD, BRANCH_SUBTRACT
from mechopt.sim.four_bar.load import RockerLoad
from mechopt.sim.four_bar.mechanism import FourBar
from mechopt.sim.four_bar.motion import LAW_CODES, MotionLaw
from mechopt.sim.four_bar.problem import FourBarProblem
from mechopt.sim.four_bar.reconstruction import read_motor_table, reconstruct
from mechopt.sim.four_bar.simulate import ENGINES
from mechopt.studies.study_file import StudyFile
from mechopt.studies.variable_entry import study_variable

__all__ = ["problem_from_study"]

_MECHANISM_KEYS = {"ground", "assembly_branch", "coupler_mass_kg", "toggle_margin_deg", "pivot_c_mm", "j0_kgm2",
                   "i_r_kgm2"}
_RECONSTRUCTION_KEYS = {"table", "original_mm", "theta_start_deg", "theta_end_deg", "n_starts", "seed"}
_MOTION_KEYS = {"law", "stroke_time_s", "psi_start_deg", "psi_end_deg"}
_LOAD_KEYS = {"rocker_Nm", "table"}
_SAMPLING_KEYS = {"engine", "toggle_relax_deg", "box_extend"}
_BRANCHES = {"theta1": BRANCH_SUBTRACT, "theta2": BRANCH_ADD}
_NAMES = ("oa", "ab", "bc")
#: Keys of a length written as a table (always in mm).
_LENGTH_KEYS = ("bounds", "lower", "upper", "step", "integer", "values")


def problem_from_study(study: StudyFile, options: dict[str, Any]) -> FourBarProblem:
    """The four-bar problem of a study file.

    Parameters
    ----------
    study : StudyFile
        The parsed study file.
    options : dict
        Overrides from the command line: ``engine`` (``"pymunk"``, ``"analytic"``, ``"exudyn"``).

    Raises
    ------
    StudyError
        A missing, unknown or ill-typed key, named with its file.
    """
    try:
        return _problem(study, options)
    except StudyError:
        raise
    except MechoptError as exc:
        raise StudyError(f"{study.where}: {exc}") from None


def _problem(study: StudyFile, options: dict[str, Any]) -> FourBarProblem:
    mech = study.table("mechanism", _MECHANISM_KEYS | {"kind"})
    branch_name = study.string(mech, "assembly_branch", "mechanism", "theta1", _BRANCHES)
    motion_cfg = study.table("motion", _MOTION_KEYS)
    law = study.string(motion_cfg, "law", "motion", "quintic", LAW_CODES)
    stroke_time = study.number(motion_cfg, "stroke_time_s", "motion", positive=True)
    ground = study.string(mech, "ground", "mechanism", "explicit", ("reconstruction", "explicit"))
    if ground == "reconstruction":
        rec_cfg = study.table("reconstruction", _RECONSTRUCTION_KEYS)
        table = study.data_path(study.string(rec_cfg, "table", "reconstruction"), "reconstruction.table")
        original = rec_cfg.get("original_mm")
        if not isinstance(original, dict) or set(original) != set(_NAMES):
            raise StudyError(f"{study.where}: key reconstruction.original_mm must be {{ oa = …, ab = …, bc = … }} "
                             "in mm")
        rec = _reconstruct_cached(
            str(table), tuple(study.number(original, k, "reconstruction.original_mm", positive=True) for k in _NAMES),
            study.number(rec_cfg, "theta_start_deg", "reconstruction"),
            study.number(rec_cfg, "theta_end_deg", "reconstruction"),
            study.integer(rec_cfg, "n_starts", "reconstruction", 400, minimum=1),
            study.integer(rec_cfg, "seed", "reconstruction", 0),
        )
        if _BRANCHES[branch_name] != rec.inverse_branch:
            raise StudyError(f"{study.where}: mechanism.assembly_branch = {branch_name!r} does not assemble the "
                             "original as the table does")
        pivot, j0, i_r, load = rec.pivot_c, rec.j0, rec.i_r, rec.load
        reconstruction = rec
        psi_start, psi_end = rec.psi_start, rec.psi_end
    else:
        pivot = tuple(study.numbers(mech, "pivot_c_mm", "mechanism", length=2))
        j0 = study.number(mech, "j0_kgm2", "mechanism", minimum=0.0)
        i_r = study.number(mech, "i_r_kgm2", "mechanism", minimum=0.0)
        psi_start = np.radians(study.number(motion_cfg, "psi_start_deg", "motion"))
        psi_end = np.radians(study.number(motion_cfg, "psi_end_deg", "motion"))
        load = _explicit_load(study)
        reconstruction = None
    mechanism = FourBar(
        pivot_c=pivot, j0=j0, i_r=i_r, motion=MotionLaw(psi_start, psi_end, stroke_time, law), load=load,
        coupler_mass=study.number(mech, "coupler_mass_kg", "mechanism", 0.0, minimum=0.0),
        branch=_BRANCHES[branch_name],
        toggle_margin_deg=study.number(mech, "toggle_margin_deg", "mechanism", 15.0, minimum=0.0, maximum=89.9),
    )
    sampling = study.table("sampling", _SAMPLING_KEYS, required=False)
    engine = options.get("engine") or study.string(sampling, "engine", "sampling", "pymunk", ENGINES)
    box, kinds = _box(study)
    return FourBarProblem(
        mechanism=mechanism, box=box, engine=engine, name=str(study.config.get("name", study.path.parent.name)),
        toggle_relax_deg=study.number(sampling, "toggle_relax_deg", "sampling", 5.0, minimum=0.0),
        box_extend=study.number(sampling, "box_extend", "sampling", 0.15, minimum=0.0, maximum=1.0),
        reconstruction=reconstruction, kinds=kinds if any(kinds) else None,
    )


def _box(study: StudyFile) -> tuple[np.ndarray, tuple[dict[str, Any], ...]]:
    """The bounds of the three lengths (mm) and the kind of each (``{}``, ``{"step": 0.1}``...)."""
    variables = study.table("variables", _NAMES)
    box, kinds = [], []
    for name in _NAMES:
        if name not in variables:
            raise StudyError(f"{study.where}: missing key variables.{name}")
        v = study_variable(study, name, variables[name], "mm", keys=_LENGTH_KEYS)
        if not 0 < v.lower < v.upper:
            raise StudyError(f"{study.where}: key variables.{name} = [{v.lower}, {v.upper}] must satisfy 0 < lower < "
                             "upper (mm)")
        box.append((v.lower, v.upper))
        kinds.append({k: getattr(v, k) for k in ("step", "values") if getattr(v, k) is not None}
                     | ({"integer": True} if v.integer else {}))
    return np.array(box), tuple(kinds)


def _explicit_load(study: StudyFile) -> RockerLoad:
    load_cfg = study.table("load", _LOAD_KEYS, required=False) or {"rocker_Nm": 0.0}
    if "table" in load_cfg:
        table = study.data_path(study.string(load_cfg, "table", "load"), "load.table")
        try:
            data = np.loadtxt(table, delimiter=",", skiprows=1, ndmin=2)
        except ValueError as exc:
            raise StudyError(f"{study.where}: load table {table.name}: {exc}") from None
        return RockerLoad.from_table(np.radians(data[:, 0]), data[:, 1])
    return RockerLoad.constant(study.number(load_cfg, "rocker_Nm", "load", 0.0))


@functools.lru_cache(maxsize=4)
def _reconstruct_cached(table_path: str, original: tuple, theta_start_deg: float, theta_end_deg: float,
                        n_starts: int, seed: int):
    table = read_motor_table(Path(table_path))
    return reconstruct(table, original, np.radians(theta_start_deg), np.radians(theta_end_deg), n_starts, seed)
