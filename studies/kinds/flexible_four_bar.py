"""``kind = "flexible-four-bar"``: a study file read into a flexible four-bar design problem (paper 004, §3.2).

Sections read here: ``[variables]`` (any of l1, l2, l3, l4, E3, rho3, h3, a3, E4, rho4, h4, a4 with their bounds in
mm, Pa, kg/m³), ``[mechanism]`` (crank rate, assembly branch and the values of the variables that are not free),
``[simulation]``, ``[objective]`` (the target design, all twelve variables) and the optional ``[figures]``
(``responses``: the designs drawn against the target, e.g. ``["optimum", "table8_HO"]``).
"""

from __future__ import annotations

from typing import Any

from mechopt.errors import InputError, StudyError
from mechopt.sim.flexible_four_bar import ENGINES, FlexibleFourBar
from mechopt.sim.flexible_four_bar.problem import ALL_VARIABLES, FlexibleFourBarProblem
from mechopt.studies.study_file import StudyFile

__all__ = ["problem_from_study"]

_SIMULATION_KEYS = {"engine", "t_end_s", "n_samples", "n_elements", "n_modes", "damping_beta_s", "geometric_stiffness"}


def _bounds(study: StudyFile) -> dict[str, tuple[float, float]]:
    var = study.table("variables", allowed=ALL_VARIABLES)
    if not var:
        raise StudyError(f"{study.where}: section [variables] names none of {', '.join(ALL_VARIABLES)}")
    bounds = {}
    for k in var:
        lo, hi = study.numbers(var, k, "variables", length=2)
        if not 0.0 < lo < hi:
            raise StudyError(f"{study.where}: key variables.{k} = {[lo, hi]}; expected 0 < lower < upper")
        bounds[k] = (lo, hi)
    return bounds


def _base(study: StudyFile, mech: dict[str, Any]) -> FlexibleFourBar:
    sim = study.table("simulation", allowed=_SIMULATION_KEYS, required=False)
    geometric = sim.get("geometric_stiffness", False)
    if not isinstance(geometric, bool):
        raise StudyError(f"{study.where}: key simulation.geometric_stiffness = {geometric!r} must be true or false")
    d = FlexibleFourBar()
    return FlexibleFourBar(
        omega=study.number(mech, "omega_rad_s", "mechanism", positive=True),
        branch=study.integer(mech, "branch", "mechanism", default=d.branch),
        t_end=study.number(sim, "t_end_s", "simulation", default=d.t_end, positive=True),
        n_samples=study.integer(sim, "n_samples", "simulation", default=d.n_samples, minimum=2),
        n_elements=study.integer(sim, "n_elements", "simulation", default=d.n_elements, minimum=2),
        n_modes=study.integer(sim, "n_modes", "simulation", default=d.n_modes, minimum=1),
        beta=study.number(sim, "damping_beta_s", "simulation", default=d.beta, minimum=0.0),
        geometric_stiffness=geometric)


def problem_from_study(study: StudyFile, options: dict[str, Any]) -> FlexibleFourBarProblem:
    """Build the problem from a study file (sections [variables], [mechanism], [simulation], [objective]).

    Parameters
    ----------
    study : StudyFile
        The parsed study.
    options : dict
        CLI overrides; ``{"engine": "modal" | "exudyn"}`` is read, other keys are not this plug-in's.

    Returns
    -------
    FlexibleFourBarProblem
    """
    bounds = _bounds(study)
    mech = study.table("mechanism", allowed={"omega_rad_s", "branch", *ALL_VARIABLES})
    clash = sorted(set(mech) & set(bounds))
    if clash:
        raise StudyError(f"{study.where}: key mechanism.{clash[0]} is a variable; fix it here or free it in "
                         f"[variables], not both")
    fixed = {k: study.number(mech, k, "mechanism", positive=True) for k in ALL_VARIABLES if k in mech}
    obj = study.table("objective", allowed={"target"})
    target_table = obj.get("target")
    if not isinstance(target_table, dict):
        raise StudyError(f"{study.where}: key objective.target must be a table of the twelve variables")
    unknown = sorted(set(target_table) - set(ALL_VARIABLES))
    if unknown:
        raise StudyError(f"{study.where}: unknown key objective.target.{unknown[0]}; "
                         f"expected {', '.join(ALL_VARIABLES)}")
    target = {k: study.number(target_table, k, "objective.target", positive=True) for k in ALL_VARIABLES}
    sim = study.table("simulation", allowed=_SIMULATION_KEYS, required=False)
    engine = options.get("engine") or study.string(sim, "engine", "simulation", default="modal", choices=ENGINES)
    name = study.config.get("name", "flexible-four-bar")
    figs = study.table("figures", allowed={"responses"}, required=False)
    drawn = figs.get("responses")
    if drawn is not None and not (isinstance(drawn, list) and all(isinstance(v, str) for v in drawn)):
        raise StudyError(f"{study.where}: key figures.responses = {drawn!r} must be a list of design names")
    try:
        return FlexibleFourBarProblem(bounds=bounds, fixed=fixed, target=target, engine=engine,
                                      base=_base(study, mech), name=str(name),
                                      figure_designs=None if drawn is None else tuple(drawn))
    except InputError as err:
        raise StudyError(f"{study.where}: {err}") from None
