"""``kind = "path-synthesis"``: a study file read into paper 000's slider-crank path-synthesis problem.

Sections read here: ``[variables]`` (bounds of a1 ... a8, all eight; lengths in the points' unit, a6 in rad),
``[points]`` (``desired``: the CSV ``i,x,y`` of the desired points, beside the study file or in the packaged study),
the optional ``[constraints]`` (``max_bar_ratio``: the largest ratio of the longest to the shortest of a1, a2, |a3|,
|a4|; the Grashof margin is always imposed) and the optional ``[simulation]`` (``n_grid``: crank angles sampled
before the closest-point refinement).
"""

from __future__ import annotations

from typing import Any

from mechopt.errors import InputError, StudyError
from mechopt.sim.path_synthesis.closest_point import DEFAULT_GRID
from mechopt.sim.path_synthesis.points import read_points
from mechopt.sim.path_synthesis.problem import VARIABLES, PathSynthesisProblem
from mechopt.studies.kinds.slider_crank_common import check_options
from mechopt.studies.study_file import StudyFile

__all__ = ["problem_from_study"]


def _bounds(study: StudyFile) -> dict[str, tuple[float, float]]:
    var = study.table("variables", allowed=VARIABLES)
    missing = [k for k in VARIABLES if k not in var]
    if missing:
        raise StudyError(f"{study.where}: missing key variables.{missing[0]}; the study needs bounds of all of "
                         f"{', '.join(VARIABLES)}")
    bounds = {}
    for k in VARIABLES:
        lo, hi = study.numbers(var, k, "variables", length=2)
        if not lo < hi:
            raise StudyError(f"{study.where}: key variables.{k} = {[lo, hi]}; expected lower < upper")
        if k in ("a1", "a2") and lo <= 0:
            raise StudyError(f"{study.where}: key variables.{k} = {[lo, hi]}; a bar length needs lower > 0")
        bounds[k] = (lo, hi)
    return bounds


def problem_from_study(study: StudyFile, options: dict[str, Any]) -> PathSynthesisProblem:
    """The problem of a study file of kind ``path-synthesis``.

    Parameters
    ----------
    study : StudyFile
        The parsed study.
    options : dict
        CLI overrides; only no engine (or ``"analytic"``) is accepted: the coupler curve is closed-form.

    Returns
    -------
    PathSynthesisProblem

    Raises
    ------
    StudyError
        A missing or malformed key, an unreadable points file, or bounds that hold no design whose crank turns.
    """
    check_options(study, options)
    bounds = _bounds(study)
    pts = study.table("points", allowed=("desired",))
    path = study.data_path(study.string(pts, "desired", "points"), "points.desired")
    cons = study.table("constraints", allowed=("max_bar_ratio",), required=False)
    ratio = study.number(cons, "max_bar_ratio", "constraints", minimum=1.0) if "max_bar_ratio" in cons else None
    sim = study.table("simulation", allowed=("n_grid",), required=False)
    n_grid = study.integer(sim, "n_grid", "simulation", default=DEFAULT_GRID, minimum=16)
    a5_smallest = 0.0 if bounds["a5"][0] <= 0.0 <= bounds["a5"][1] else min(abs(v) for v in bounds["a5"])
    if bounds["a2"][1] - bounds["a1"][0] - a5_smallest < 0:
        raise StudyError(f"{study.where}: no feasible design: a2 <= {bounds['a2'][1]:g} never exceeds "
                         f"a1 + |a5| >= {bounds['a1'][0] + a5_smallest:g}, so no crank turns fully")
    try:
        points = read_points(path)
        return PathSynthesisProblem(points, bounds, max_ratio=ratio, name=str(study.config.get("name",
                                    "path-synthesis")), n_grid=n_grid)
    except InputError as err:
        raise StudyError(f"{study.where}: {err}") from None
