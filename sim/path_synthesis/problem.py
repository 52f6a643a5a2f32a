"""Paper 000's path synthesis as a mechopt design problem: eight dimensions a1..a8, unprescribed timing, E minimised.

Variables (a1, ..., a8) of :mod:`.coupler` (lengths in the points' unit, a6 in rad); objective E of Eq. 11, the sum
of squared distances from each desired point to the closest point of the coupler curve on the better branch
(:mod:`.path_error`); constraints the margins of :mod:`.feasibility` (``grashof`` always, ``bar_ratio`` when a
largest bar ratio is given).  :attr:`residuals` names the output holding the signed distances, E = Σ r², for
least-squares methods.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InfeasibleDesignError, InputError
from mechopt.optimize.problem import DesignProblem, Variable, as_design_array
from mechopt.sim.path_synthesis.closest_point import DEFAULT_GRID
from mechopt.sim.path_synthesis.feasibility import CONSTRAINTS, GRASHOF, bar_ratio_margin, grashof_margin, margins
from mechopt.sim.path_synthesis.path_error import PathFit, fit_path

__all__ = ["VARIABLES", "PathSynthesisProblem"]

#: The design variables of paper 000 (Fig. 3), in order.
VARIABLES = ("a1", "a2", "a3", "a4", "a5", "a6", "a7", "a8")
_LABELS = {"a1": "a1 (crank)", "a2": "a2 (rod)", "a3": "a3 (P along rod)", "a4": "a4 (P across rod)",
           "a5": "a5 (slider offset)", "a6": "a6 (rotation)", "a7": "a7 (y shift)", "a8": "a8 (x shift)"}


class PathSynthesisProblem(DesignProblem):
    """A slider-crank whose coupler point passes near desired points (paper 000, unprescribed timing).

    Parameters
    ----------
    points : (N, 2) array_like
        Desired points (lengths), N >= 3.
    bounds : mapping of str to (float, float)
        Bounds of each of a1 ... a8 (lengths; a6 in rad).  a1 and a2 must stay > 0.
    max_ratio : float, optional
        Largest ratio of the longest to the shortest of a1, a2, |a3|, |a4| (paper example 1: 3); None: none.
    name : str
        Name of the problem (the study's).
    n_grid : int
        Crank angles sampled before the closest-point refinement.
    """

    outputs = ("E", "branch", "E_other_branch", "rms_distance", "max_distance")
    objective = "E"
    residuals = "residuals"
    fit = "value"

    def __init__(self, points: np.ndarray, bounds: Mapping[str, tuple[float, float]], max_ratio: float | None = None,
                 name: str = "path-synthesis", n_grid: int = DEFAULT_GRID) -> None:
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 3 or not np.all(np.isfinite(pts)):
            raise InputError(f"path synthesis: points must be (N, 2) finite numbers with N >= 3, got {pts.shape}")
        missing = [k for k in VARIABLES if k not in bounds]
        unknown = sorted(set(bounds) - set(VARIABLES))
        if missing or unknown:
            raise InputError(f"path synthesis: bounds {'lack ' + missing[0] if missing else 'name ' + unknown[0]}; "
                             f"expected {', '.join(VARIABLES)}")
        self.variables = tuple(Variable(k, *bounds[k], unit="rad" if k == "a6" else "", label=_LABELS[k])
                               for k in VARIABLES)
        for k in ("a1", "a2"):
            if bounds[k][0] <= 0:
                raise InputError(f"path synthesis: {k} is a bar length; its lower bound {bounds[k][0]} must be > 0")
        if max_ratio is not None and not max_ratio >= 1.0:
            raise InputError(f"path synthesis: max_ratio = {max_ratio!r} must be >= 1")
        self.points = pts
        self.max_ratio = None if max_ratio is None else float(max_ratio)
        self.constraints = CONSTRAINTS if self.max_ratio is not None else GRASHOF
        self.name = name
        self.n_grid = int(n_grid)

    def margins(self, X: np.ndarray) -> np.ndarray:
        """The smooth pieces of the ``grashof`` (and ``bar_ratio``) margins of designs X (n, 8), lengths
        (:func:`~mechopt.sim.path_synthesis.feasibility.margins`)."""
        return margins(X, self.max_ratio)

    def path_fit(self, x: np.ndarray) -> PathFit:
        """Closest points of design ``x`` on its better branch (no feasibility check)."""
        return fit_path(as_design_array(x, 8, "design")[0], self.points, self.n_grid)

    def evaluate(self, x: np.ndarray) -> dict[str, Any]:
        """E of Eq. 11 and its parts for design ``x``.

        Returns
        -------
        dict
            ``E`` (length²), ``branch`` (K = ±1 of the smaller E), ``E_other_branch``, ``rms_distance`` and
            ``max_distance`` (lengths), ``residuals`` (signed distances, E = Σ r²) and ``phi`` (crank angle of each
            closest point, rad).

        Raises
        ------
        InfeasibleDesignError
            A negative margin (the crank cannot turn fully, or the bar ratio is exceeded).
        """
        a = as_design_array(x, 8, "design")[0]
        for name, m in self.named_margins(a).items():
            if m < 0:
                why = "the crank cannot turn fully" if name == "grashof" else \
                    f"the longest bar exceeds {self.max_ratio:g} times the shortest"
                raise InfeasibleDesignError(f"{self.describe(a)}: {why} ({name} margin {m:.4g} < 0)")
        f = self.path_fit(a)
        d = f.distances
        return {"E": f.E, "branch": float(f.branch), "E_other_branch": f.E_other,
                "rms_distance": float(np.sqrt(f.E / d.size)), "max_distance": float(d.max()),
                "residuals": f.residuals.tolist(), "phi": f.phi.tolist()}

    def settings(self) -> dict[str, Any]:
        """The desired points, the bar ratio and the closest-point grid (they change E)."""
        return {"points": self.points.round(12).tolist(), "max_ratio": self.max_ratio, "n_grid": self.n_grid,
                "branches": "both, the smaller E kept"}

    def active_bounds(self, x: np.ndarray, tol: float = 1e-6, margin_tol: float = 1e-3) -> list[str]:
        """The bounds and constraints active at design ``x``.

        A bound is active within ``tol`` times its variable's range, a constraint within ``margin_tol`` times the
        longest of a1, a2, |a3|, |a4|.

        Returns
        -------
        list of str
            E.g. ``["a2 = upper 15", "bar_ratio margin 2e-07"]``; empty when the design is interior.
        """
        a = as_design_array(x, 8, "design")[0]
        out = []
        for v, xi in zip(self.variables, a, strict=True):
            w = tol * (v.upper - v.lower)
            if xi <= v.lower + w:
                out.append(f"{v.name} = lower {v.lower:g}")
            elif xi >= v.upper - w:
                out.append(f"{v.name} = upper {v.upper:g}")
        scale = float(np.max(np.abs(a[:4])))
        for name, m in self.named_margins(a).items():
            if abs(m) <= margin_tol * scale:
                out.append(f"{name} margin {m:.2g}")
        return out

    def named_margins(self, x: np.ndarray) -> dict[str, float]:
        """``{"grashof": a2 − a1 − |a5|, "bar_ratio": m·min − max}`` of one design (the latter with a bar ratio)."""
        a = as_design_array(x, 8, "design")
        out = {"grashof": float(grashof_margin(a)[0])}
        if self.max_ratio is not None:
            out["bar_ratio"] = float(bar_ratio_margin(a, self.max_ratio)[0])
        return out

    def figures(self, designs: Mapping[str, np.ndarray], out: Path) -> dict[str, Path]:
        """Desired points, coupler curve and linkage poses of each design side by side; the optimum (or the first
        design) animated over one crank revolution."""
        from mechopt.sim.path_synthesis.figures import animate_design, plot_designs

        out = Path(out)
        # every design whose crank turns (its curve exists), even one outside the bar ratio
        drawn = {k: np.asarray(v, dtype=float) for k, v in designs.items()
                 if self.named_margins(v)["grashof"] >= 0}
        if not drawn:
            return {}
        notes = {k: self.active_bounds(v) for k, v in drawn.items()}
        fits = {k: self.path_fit(v) for k, v in drawn.items()}
        made = {"Desired points, coupler curves and linkages of the designs":
                plot_designs(self.points, drawn, fits, notes, out / "path_synthesis_designs.png", self.name)}
        label = "optimum" if "optimum" in drawn else next(iter(drawn))
        made[f"One crank revolution of the {label} design"] = animate_design(
            self.points, drawn[label], fits[label], out / f"path_synthesis_{label}.gif", label)
        return made
