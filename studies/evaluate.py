"""The simulator as the sampling machinery calls it: a picklable callable with the settings that identify it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from mechopt.errors import InputError
from mechopt.sim.fourbar.mechanism import FourBar
from mechopt.sim.fourbar.simulate import ENGINES, simulate

from .store import settings_hash


@dataclass(frozen=True)
class Evaluator:
    """Simulate one design and return its objective values; picklable, so it runs in worker processes and on Dask.

    Parameters
    ----------
    mechanism : FourBar
        The study's mechanism.
    engine : str
        ``"pymunk"`` or ``"analytic"``.
    study : str
        Name of the study (part of the settings hash).
    """

    mechanism: FourBar
    engine: str = "pymunk"
    study: str = ""

    def __post_init__(self) -> None:
        if self.engine not in ENGINES:
            raise InputError(f"unknown engine {self.engine!r}; expected one of {', '.join(ENGINES)}")

    def __call__(self, design: tuple[float, float, float]) -> dict:
        """T_RMS and T_max (N·m) of ``design`` (mm), with the feasibility flag and step in ``extra``."""
        result = simulate(np.asarray(design, dtype=float), self.mechanism, engine=self.engine)
        return {"t_rms": result.t_rms, "t_max": result.t_max, "feasible": bool(result.feasible), "dt": result.dt}

    def settings(self) -> dict:
        """Everything that changes the simulated values: study, engine, mechanism numbers, engine version."""
        m = self.mechanism
        return {
            "study": self.study,
            "engine": self.engine,
            "engine_version": 1,
            "pivot_c_mm": list(m.pivot_c),
            "j0": m.j0,
            "i_r": m.i_r,
            "coupler_mass": m.coupler_mass,
            "psi": [m.psi_start, m.psi_end],
            "stroke_time_s": m.motion.t_stroke,
            "law": m.motion.law,
            "load_coefs": float(np.sum(np.abs(m.load.coefs))),
            "branch": m.branch,
        }

    def settings_hash(self) -> str:
        """Hash of :meth:`settings`, the key of this evaluator's rows in the sample store."""
        return settings_hash(self.settings())
