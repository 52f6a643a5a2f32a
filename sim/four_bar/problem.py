"""The four-bar as a design problem: (|OA|, |AB|, |BC|) in mm, T_RMS of the motor torque minimised.

:class:`FourBarProblem` binds a :class:`~mechopt.sim.four_bar.mechanism.FourBar` (everything but the three lengths)
and an engine to mechopt's design-problem protocol: the five feasibility margins as constraints, the torque
simulation as evaluator, and every number of the mechanism in the fingerprint (the whole load table, the toggle
margin, the engine) so that a changed study never reuses another's samples.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.problem import DesignProblem, Variable
from mechopt.sim.four_bar.feasibility import (
    MARGIN_NAMES,
    N_CHECK,
    check_feasibility,
    constraint_margins,
    toggle_angle_deg,
)
from mechopt.sim.four_bar.mechanism import FourBar
from mechopt.sim.four_bar.simulate import ENGINES, simulate

__all__ = ["ENGINE_VERSIONS", "FourBarProblem"]

#: Bumped when an engine's numerics change, so that stored samples of the old numerics are not reused.
ENGINE_VERSIONS = {"pymunk": 1, "analytic": 1, "exudyn": 1}

_LABELS = {"oa": "|OA|", "ab": "|AB|", "bc": "|BC|"}


@dataclass(frozen=True, eq=False, repr=False)
class FourBarProblem(DesignProblem):
    """Minimise the RMS motor torque of a four-bar driven through a prescribed rocker motion.

    Parameters
    ----------
    mechanism : FourBar
        Pivot C, inertias, rocker load, motion law, branch, toggle margin.
    box : (3, 2) array_like
        Bounds of |OA|, |AB|, |BC| (mm).
    kinds : tuple of 3 dicts, optional
        The kind of each length when it is discrete, as keyword arguments of
        :class:`~mechopt.optimize.variable.Variable` (``{"step": 0.1}`` for a drawing at 0.1 mm); ``{}`` continuous.
    engine : str
        ``"pymunk"``, ``"analytic"`` or ``"exudyn"``.
    name : str
        Study name.
    toggle_relax_deg : float
        Lines of the model may be sampled this far below the toggle margin (deg): a design rule, not physics.
    box_extend : float
        ... and this far beyond the box, as a fraction of its width (the box is a choice, the mechanism still moves).
    n_check_search : int
        ψ samples per design of the cheaper feasibility screen used on search grids.
    """

    mechanism: FourBar
    box: Any
    engine: str = "pymunk"
    name: str = "four-bar"
    toggle_relax_deg: float = 5.0
    box_extend: float = 0.15
    n_check_search: int = 61
    #: How the mechanism was recovered from data, when it was (for reports; its numbers are in the mechanism).
    reconstruction: Any = None
    kinds: tuple | None = None

    constraints = MARGIN_NAMES
    outputs = ("t_rms", "t_max", "toggle_margin_deg")
    objective = "t_rms"
    fit = "square"
    output_units = {"t_rms": "N·m", "t_max": "N·m", "toggle_margin_deg": "deg"}  # noqa: RUF012
    # Paper 002 plans its lines over (|OA|, |BC|, |AB|): its Δ and origin are read in as printed.
    surrogate_order = (0, 2, 1)

    @property
    def fd_step(self) -> float:  # type: ignore[override]
        """Differences above the time-stepping engines' noise (pymunk, Exudyn); fine ones for the closed form."""
        return 1e-5 if self.engine == "analytic" else 1e-3

    def __post_init__(self) -> None:
        if self.engine not in ENGINES:
            raise InputError(f"unknown engine {self.engine!r}; expected one of {', '.join(ENGINES)}")
        box = np.asarray(self.box, dtype=float)
        if box.shape != (3, 2):
            raise InputError(f"the four-bar's box must be 3 (lower, upper) pairs in mm, got shape {box.shape}")
        object.__setattr__(self, "box", tuple(map(tuple, box.tolist())))

    @property
    def variables(self) -> tuple[Variable, ...]:  # type: ignore[override]
        return tuple(Variable(n, lo, hi, "mm", _LABELS[n], **kind)
                     for n, (lo, hi), kind in zip(_LABELS, self.box, self.kinds or ({}, {}, {}), strict=True))

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        """T_RMS and T_max (N·m) and the toggle margin (deg: how far the crank-coupler angle at A stays from the
        dead-centre line over the stroke, min of ζ and 180° − ζ) of design ``x`` = (|OA|, |AB|, |BC|) in mm; raises
        InfeasibleDesignError if it cannot be driven through the stroke."""
        x = np.asarray(x, dtype=float)
        result = simulate(x, self.mechanism, engine=self.engine)
        return {"t_rms": float(result.t_rms), "t_max": float(result.t_max), "dt": float(result.dt),
                "feasible": bool(result.feasible), "toggle_margin_deg": toggle_angle_deg(x, self.mechanism)}

    def evaluate_batch(self, X: np.ndarray) -> np.ndarray:
        """T_RMS (N·m) of many designs (n, 3) by the analytic engine (numba), for brute-force ground truths."""
        from mechopt.sim.four_bar.analytic import analytic_batch

        t_rms, _ = analytic_batch(np.atleast_2d(np.asarray(X, dtype=float)), self.mechanism, check=False)
        return t_rms

    def margins(self, X: np.ndarray) -> np.ndarray:
        """Assembly (mm, at both ends and along the stroke), monotonic crank (deg) and toggle (deg) margins."""
        return constraint_margins(np.atleast_2d(X), self.mechanism)

    def screen(self, X: np.ndarray) -> np.ndarray:
        """Feasibility with a coarser along-stroke check, for search grids of millions of points."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        ok = self.in_box(X) & np.all(X > 0, axis=1)
        if ok.any():
            ok[ok] = check_feasibility(X[ok], self.mechanism, n_check=self.n_check_search).feasible
        return ok

    def sampleable(self, X: np.ndarray) -> np.ndarray:
        """Designs that still move through the stroke, within the relaxed toggle margin and the widened box."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        ok = self.in_box(X, self.box_extend) & np.all(X > 0, axis=1)
        if ok.any():
            report = check_feasibility(X[ok], self.mechanism, n_check=N_CHECK)
            with np.errstate(invalid="ignore"):
                ok[ok] = report.movable & (report.toggle_deg >= -self.toggle_relax_deg)
        return ok

    def settings(self) -> dict[str, Any]:
        m = self.mechanism
        return {
            "engine": self.engine,
            "engine_version": ENGINE_VERSIONS.get(self.engine, 1),
            "pivot_c_mm": list(m.pivot_c),
            "j0_kgm2": m.j0,
            "i_r_kgm2": m.i_r,
            "coupler_mass_kg": m.coupler_mass,
            "psi_rad": [m.psi_start, m.psi_end],
            "stroke_time_s": m.motion.t_stroke,
            "law": m.motion.law,
            # The whole table: a summary (the old sum of |coefficients|) lets two different loads share samples.
            "load_breaks_rad": np.asarray(m.load.breaks).tolist(),
            "load_coefs_Nm": np.asarray(m.load.coefs).tolist(),
            "branch": m.branch,
            # The stored 'feasible' flag depends on it.
            "toggle_margin_deg": m.toggle_margin_deg,
        }

    def describe(self, x: np.ndarray) -> str:
        x = np.ravel(x)
        return f"|OA|={x[0]:.3f} |AB|={x[1]:.3f} |BC|={x[2]:.3f} mm"

    def figures(self, designs: Mapping[str, np.ndarray], out: Path) -> dict[str, Path]:
        """Torque over the cycle of every design, the mechanisms at ψ_start and ψ_end, the optimum's cycle (GIF)."""
        from mechopt.sim.four_bar.figures import animate_cycle, plot_mechanisms, plot_torque_comparison

        results = {name: simulate(np.asarray(x, float), self.mechanism, engine=self.engine)
                   for name, x in designs.items()}
        files = {"Motor torque over one cycle": plot_torque_comparison(results, Path(out) / "torque_comparison.png"),
                 "Mechanisms at ψ_start and ψ_end": plot_mechanisms(dict(designs), self.mechanism,
                                                                     Path(out) / "mechanisms.png")}
        if "optimum" in results:
            files["The optimum through one cycle"] = animate_cycle(results["optimum"], self.mechanism,
                                                                   Path(out) / "optimum_cycle.gif")
        return files
