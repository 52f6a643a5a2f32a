"""``kind = "flexible-slider-crank"``: a study file read into a flexible slider-crank design problem.

Sections read here: ``[variables]`` (bounds of l2, l3, h in mm), ``[mechanism]``, ``[simulation]`` and
``[objective]`` (the target design and the weights of Eq. 18).
"""

from __future__ import annotations

from typing import Any

from mechopt.errors import InputError, StudyError
from mechopt.sim.flexible_slider_crank import ENGINES, MM, FlexibleSliderCrank
from mechopt.sim.flexible_slider_crank.problem import DEFAULT_BOUNDS, FlexibleSliderCrankProblem
from mechopt.studies.study_file import StudyFile

__all__ = ["problem_from_study"]


def problem_from_study(study: StudyFile, options: dict[str, Any]) -> FlexibleSliderCrankProblem:
    """Build the problem from a study file (sections [variables], [mechanism], [simulation], [objective]).

    Parameters
    ----------
    study : StudyFile
        The parsed study.
    options : dict
        CLI overrides; ``{"engine": "modal" | "exudyn"}`` is read, other keys are not this plug-in's.

    Returns
    -------
    FlexibleSliderCrankProblem
    """
    var = study.table("variables", allowed=DEFAULT_BOUNDS)
    bounds = {}
    for k in DEFAULT_BOUNDS:
        lo, hi = study.numbers(var, k, "variables", length=2)
        if not 0.0 < lo < hi:
            raise StudyError(f"{study.where}: key variables.{k} = {[lo, hi]}; expected 0 < lower < upper (mm)")
        bounds[k] = (lo, hi)
    mech = study.table("mechanism", allowed={"E_Pa", "rho_kg_m3", "width_mm", "slider_mass_kg", "omega_rad_s"})
    sim = study.table("simulation", allowed={"engine", "t_end_s", "n_samples", "n_elements", "n_modes",
                                             "damping_beta_s", "axial_stiffening"}, required=False)
    obj = study.table("objective", allowed={"weights_D_V_A", "target"})
    target_table = obj.get("target")
    if not isinstance(target_table, dict):
        raise StudyError(f"{study.where}: key objective.target must be a table {{l2 = .., l3 = .., h = ..}} (mm)")
    unknown = sorted(set(target_table) - set(DEFAULT_BOUNDS))
    if unknown:
        raise StudyError(f"{study.where}: unknown key objective.target.{unknown[0]}; expected l2, l3, h")
    target = {k: study.number(target_table, k, "objective.target", positive=True) for k in DEFAULT_BOUNDS}
    weights = study.numbers(obj, "weights_D_V_A", "objective", length=3, default=[0.4, 0.3, 0.3])
    engine = options.get("engine") or study.string(sim, "engine", "simulation", default="modal", choices=ENGINES)
    stiffening = sim.get("axial_stiffening", False)
    if not isinstance(stiffening, bool):
        raise StudyError(f"{study.where}: key simulation.axial_stiffening = {stiffening!r} must be true or false")
    defaults = FlexibleSliderCrank()
    try:
        base = FlexibleSliderCrank(
            E=study.number(mech, "E_Pa", "mechanism", positive=True),
            rho=study.number(mech, "rho_kg_m3", "mechanism", positive=True),
            a=study.number(mech, "width_mm", "mechanism", positive=True) * MM,
            slider_mass=study.number(mech, "slider_mass_kg", "mechanism", positive=True),
            omega=study.number(mech, "omega_rad_s", "mechanism", positive=True),
            t_end=study.number(sim, "t_end_s", "simulation", default=defaults.t_end, positive=True),
            n_samples=study.integer(sim, "n_samples", "simulation", default=defaults.n_samples, minimum=2),
            n_elements=study.integer(sim, "n_elements", "simulation", default=defaults.n_elements, minimum=2),
            n_modes=study.integer(sim, "n_modes", "simulation", default=defaults.n_modes, minimum=1),
            beta=study.number(sim, "damping_beta_s", "simulation", default=defaults.beta, minimum=0.0),
            axial_stiffening=stiffening)
        return FlexibleSliderCrankProblem(bounds=bounds, target_mm=target, weights=tuple(weights), engine=engine,
                                          base=base)
    except InputError as err:
        raise StudyError(f"{study.where}: {err}") from None
