"""The flexible four-bar study of paper 004 (Section 3.2) as a mechopt design problem: match a target's responses.

The paper's twelve variables are X = [l1 l2 l3 l4 E3 ρ3 h3 a3 E4 ρ4 h4 a4] (mm, Pa, kg/m³; names ``l1`` ... ``a4``,
``rho3``, ``rho4``).  A problem frees any subset of them (in that order) and holds the others at fixed values.  In
the linear bending model a link's material and section enter only through κ = E h² / ρ (the width a drops out of
EI/(ρA) = E h²/(12 ρ), and E, ρ, h are tied in κ), so (l1, l2, l3, l4, h3, h4) with E, ρ and a fixed spans every
response the twelve can give; the twelve-variable problem has a 6-dimensional valley of equivalent optima.

The objective is the paper's Eq. 25 read as five unweighted terms (:mod:`.response`) against the responses of a
target design simulated by the same engine, so the global optimum is known: f = 0 at the target.  Constraints: the
crank-rocker inequalities of Eq. 26 (mm), l1 + l3 − l2 − l4, l1 + l4 − l2 − l3, l3 + l4 − l1 − l2 >= 0.  It is a
least-squares problem (:attr:`residuals`): the output ``residuals`` holds the five terms' normalised per-instant
differences (:func:`.response.residuals`), f = Σ_k sqrt(Σ_{i in term k} r_i²).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.problem import DesignProblem, Variable
from mechopt.sim.flexible_four_bar.kinematics import crank_rocker_margins
from mechopt.sim.flexible_four_bar.loads import euler_load_ratios
from mechopt.sim.flexible_four_bar.parameters import MM, FlexibleFourBar
from mechopt.sim.flexible_four_bar.response import FourBarResponse, five_term_error
from mechopt.sim.flexible_four_bar.response import residuals as term_residuals
from mechopt.sim.flexible_four_bar.simulate import ENGINES, simulate

__all__ = ["ALL_VARIABLES", "IDENTIFIABLE", "PAPER_BOUNDS", "TARGET", "FlexibleFourBarProblem"]

#: The paper's design vector X of Eq. 25, in its order.
ALL_VARIABLES = ("l1", "l2", "l3", "l4", "E3", "rho3", "h3", "a3", "E4", "rho4", "h4", "a4")
#: The variables that the responses identify (E, ρ and a of both links held fixed).
IDENTIFIABLE = ("l1", "l2", "l3", "l4", "h3", "h4")
#: Table 3's intervals (mm, Pa, kg/m³); h and a are missing in print and taken from the slider-crank's Table 2.
PAPER_BOUNDS = {"l1": (100.0, 300.0), "l2": (70.0, 200.0), "l3": (200.0, 300.0), "l4": (200.0, 300.0),
                "E3": (6.5e10, 7.5e10), "rho3": (2000.0, 3000.0), "h3": (1.0, 2.0), "a3": (20.0, 30.0),
                "E4": (6.5e10, 7.5e10), "rho4": (2000.0, 3000.0), "h4": (1.0, 2.0), "a4": (20.0, 30.0)}
#: Table 1's target: aluminium links of section 0.36e-4 m² = a h with h = 1.53075 mm (κ = 62.54 m⁴/s², the
#: slider-crank case's) and a = 23.518 mm.
TARGET = {"l1": 285.0, "l2": 100.0, "l3": 250.0, "l4": 250.0, "E3": 7.1e10, "rho3": 2660.0, "h3": 1.53075,
          "a3": 23.518, "E4": 7.1e10, "rho4": 2660.0, "h4": 1.53075, "a4": 23.518}
_UNITS = {"l": "mm", "E": "Pa", "r": "kg/m³", "h": "mm", "a": "mm"}
_LABELS = {"l1": "l1 (frame)", "l2": "l2 (crank)", "l3": "l3 (coupler)", "l4": "l4 (follower)"}


def _complete(values: Mapping[str, float], what: str) -> dict[str, float]:
    missing = [k for k in ALL_VARIABLES if k not in values]
    unknown = sorted(set(values) - set(ALL_VARIABLES))
    if missing or unknown:
        raise InputError(f"flexible four-bar: {what} {'lacks ' + missing[0] if missing else 'has ' + unknown[0]}; "
                         f"expected the twelve of {', '.join(ALL_VARIABLES)}")
    return {k: float(values[k]) for k in ALL_VARIABLES}


def four_bar_of(values: Mapping[str, float], base: FlexibleFourBar) -> FlexibleFourBar:
    """The simulation settings of a design given as all twelve variables (mm, Pa, kg/m³); the rest from ``base``."""
    v = values
    made = FlexibleFourBar.from_mm(v["l1"], v["l2"], v["l3"], v["l4"], h3=v["h3"], a3=v["a3"], h4=v["h4"],
                                   a4=v["a4"], E3=v["E3"], rho3=v["rho3"], E4=v["E4"], rho4=v["rho4"])
    return base.with_(l1=made.l1, l2=made.l2, l3=made.l3, l4=made.l4, coupler=made.coupler, follower=made.follower)


class FlexibleFourBarProblem(DesignProblem):
    """Synthesis of the flexible four-bar against a target design's five responses (paper 004, Section 3.2).

    Parameters
    ----------
    bounds : mapping of str to (float, float), optional
        The free variables (names of :data:`ALL_VARIABLES`) and their bounds; default :data:`IDENTIFIABLE` with
        :data:`PAPER_BOUNDS`.
    fixed : mapping of str to float, optional
        Values of the variables that are not free; default the target's.
    target : mapping of str to float, optional
        The target design, all twelve variables; default :data:`TARGET`.
    engine : str
        ``"modal"`` (default) or ``"exudyn"``.
    base : FlexibleFourBar, optional
        Everything else (ω, damping, elements, modes, time grid, branch).
    name : str
        Name of the problem (the study's).
    figure_designs : sequence of str, optional
        The designs drawn in the response figure of :meth:`figures` (with the target); default all given.
    """

    constraints = ("crank_rocker_1", "crank_rocker_2", "crank_rocker_3")
    outputs = ("f", "f_crank", "f_coupler", "f_follower", "f_D3", "f_D4", "kappa3", "kappa4")
    objective = "f"
    output_units = {"kappa3": "m⁴/s²", "kappa4": "m⁴/s²", "D3_peak_mm": "mm", "D4_peak_mm": "mm"}  # noqa: RUF012
    # a sum of RMS errors is a cone |δ| at the optimum; its square is smooth there (as in the slider-crank study)
    fit = "square"
    #: the output holding the five terms' normalised per-instant differences (:func:`.response.residuals`)
    residuals = "residuals"
    #: 2: evaluate returns the residuals, and the modal engine's geometric terms turn the chords as they shorten
    version = 2

    def __init__(self, bounds: Mapping[str, tuple[float, float]] | None = None,
                 fixed: Mapping[str, float] | None = None, target: Mapping[str, float] | None = None,
                 engine: str = "modal", base: FlexibleFourBar | None = None, name: str = "flexible-four-bar",
                 figure_designs: tuple[str, ...] | None = None) -> None:
        bounds = {k: PAPER_BOUNDS[k] for k in IDENTIFIABLE} if bounds is None else dict(bounds)
        unknown = sorted(set(bounds) - set(ALL_VARIABLES))
        if unknown or not bounds:
            raise InputError(f"flexible four-bar: variable {unknown[0] if unknown else '(none)'}; expected some of "
                             f"{', '.join(ALL_VARIABLES)}")
        self.free = tuple(k for k in ALL_VARIABLES if k in bounds)
        self.variables = tuple(Variable(k, *bounds[k], unit=_UNITS[k[0]], label=_LABELS.get(k, k)) for k in self.free)
        self.target_values = _complete(TARGET if target is None else target, "target")
        fixed = dict(fixed or {})
        stray = sorted(set(fixed) - (set(ALL_VARIABLES) - set(bounds)))
        if stray:
            raise InputError(f"flexible four-bar: fixed {stray[0]} is not one of the fixed variables")
        self.fixed = {k: float(fixed.get(k, self.target_values[k])) for k in ALL_VARIABLES if k not in bounds}
        if engine not in ENGINES:
            raise InputError(f"flexible four-bar: engine = {engine!r}; expected one of {', '.join(ENGINES)}")
        self.engine = engine
        self.name = name
        self.figure_designs = None if figure_designs is None else tuple(figure_designs)
        self.base = FlexibleFourBar() if base is None else base
        self.f_min = 0.0
        self.x_min = np.array([[self.target_values[k] for k in self.free]])
        self._target: FourBarResponse | None = None

    @property
    def fd_step(self) -> float:  # type: ignore[override]
        """Exudyn's Newton tolerance (1e-4) is noise to a difference; the modal model's fixed steps are smooth."""
        return 1e-3 if self.engine == "exudyn" else 1e-5

    def values(self, x: np.ndarray) -> dict[str, float]:
        """All twelve variables of design ``x`` (the free ones from ``x``, the others fixed)."""
        return {**self.fixed, **dict(zip(self.free, (float(v) for v in np.ravel(x)), strict=True))}

    def margins(self, X: np.ndarray) -> np.ndarray:
        """The crank-rocker slacks of Eq. 26 (mm) of designs X (n, d)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        cols = [X[:, self.free.index(k)] if k in self.free else np.full(X.shape[0], self.fixed[k])
                for k in ("l1", "l2", "l3", "l4")]
        return crank_rocker_margins(np.stack(cols, axis=1))

    def parameters(self, x: np.ndarray) -> FlexibleFourBar:
        """The simulation settings of design ``x``."""
        return four_bar_of(self.values(x), self.base)

    def response(self, x: np.ndarray) -> FourBarResponse:
        """Simulate design ``x`` with the problem's engine."""
        return simulate(self.parameters(x), self.engine)

    def target(self) -> FourBarResponse:
        """The target design's responses (simulated once, then kept)."""
        if self._target is None:
            self._target = simulate(four_bar_of(self.target_values, self.base), self.engine)
        return self._target

    def evaluate(self, x: np.ndarray) -> dict[str, Any]:
        """Simulate design ``x``: f and its five terms (Eq. 25), both links' κ (m⁴/s²), peak deflections (mm),
        largest compression over the Euler load (:func:`.loads.euler_load_ratios`: the linear model's validity) and
        the residuals (:func:`.response.residuals`, a list)."""
        p = self.parameters(x)
        r = simulate(p, self.engine)
        out: dict[str, Any] = five_term_error(r, self.target())
        out["residuals"] = term_residuals(r, self.target()).tolist()
        ratio3, ratio4 = euler_load_ratios(p)
        out.update(kappa3=p.coupler.kappa, kappa4=p.follower.kappa, D3_peak_mm=float(np.max(np.abs(r.D3)) / MM),
                   D4_peak_mm=float(np.max(np.abs(r.D4)) / MM), load_ratio3=ratio3, load_ratio4=ratio4)
        return out

    def settings(self) -> dict[str, Any]:
        """Everything that changes an output: engine, fixed variables, target, drive, damping, grids."""
        return {"engine": self.engine, "fixed": self.fixed, "target": self.target_values,
                "mechanism": {k: v for k, v in self.base.as_dict().items()
                              if k not in ("l1", "l2", "l3", "l4", "coupler", "follower")}}

    def figures(self, designs: Mapping[str, np.ndarray], out: Path) -> dict[str, Path]:
        """The five responses of the target and the designs of :attr:`figure_designs` in one figure; the optimum (or
        the first design) animated."""
        from mechopt.sim.flexible_four_bar.figures import animate_mechanism, plot_responses

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        runs = {}
        drawn = [k for k in designs if self.figure_designs is None or k in self.figure_designs]
        for label in drawn:
            r = self.response(designs[label])
            runs[label] = (r, five_term_error(r, self.target())["f"])
        made = {"Mid-point paths and deflections of the designs against the target":
                plot_responses(self.target(), runs, out / "flexible_four_bar_responses.png")}
        if designs:
            label = "optimum" if "optimum" in designs else next(iter(designs))
            r = runs[label][0] if label in runs else self.response(designs[label])
            made[f"The mechanism over its last crank turn ({label}), deflections magnified"] = animate_mechanism(
                r, self.parameters(designs[label]), label, out / f"flexible_four_bar_{label}.gif")
        return made
