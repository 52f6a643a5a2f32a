"""One entry point for the engines: ``simulate(design, mechanism, engine=...)``."""

from __future__ import annotations

import numpy as np

from mechopt.errors import InputError
from mechopt.sim.four_bar.analytic import simulate_analytic
from mechopt.sim.four_bar.exudyn_engine import simulate_exudyn
from mechopt.sim.four_bar.mechanism import FourBar
from mechopt.sim.four_bar.pymunk_engine import simulate_pymunk
from mechopt.sim.four_bar.result import SimulationResult

ENGINES = ("pymunk", "analytic", "exudyn")


def simulate(
    design: np.ndarray | tuple[float, float, float], mechanism: FourBar, engine: str = "pymunk", **options
) -> SimulationResult:
    """Motor torque of one design over one cycle of the prescribed motion.

    Parameters
    ----------
    design : (3,) array_like
        |OA|, |AB|, |BC| in mm.
    mechanism : FourBar
        The fixed part of the mechanism (pivot C, inertias, load, motion).
    engine : str
        ``"pymunk"`` (rigid-body motion simulation, the stand-in for CAD), ``"analytic"`` (inverse dynamics) or
        ``"exudyn"`` (Exudyn multibody simulation; exudyn is imported on first use).
    **options
        Passed to :func:`.pymunk_engine.simulate_pymunk`, :func:`.analytic.simulate_analytic` or
        :func:`.exudyn_engine.simulate_exudyn`.

    Returns
    -------
    SimulationResult
        Signed torque τ(t) (N·m), T_RMS, T_max, margins.

    Raises
    ------
    InfeasibleDesignError
        If the design cannot be driven through the stroke.
    InputError
        For an unknown engine or invalid lengths.
    """
    if engine == "pymunk":
        return simulate_pymunk(design, mechanism, **options)
    if engine == "analytic":
        return simulate_analytic(design, mechanism, **options)
    if engine == "exudyn":
        return simulate_exudyn(design, mechanism, **options)
    raise InputError(f"unknown engine {engine!r}; expected one of {', '.join(ENGINES)}")
