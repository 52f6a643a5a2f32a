"""The flexible slider-crank study of paper 004 as a mechopt design problem: match a target design's responses.

Design variables l2, l3 (crank and rod lengths) and h (rod thickness in the plane of motion), all in mm; the rod's
E, ρ and width a are fixed.  In the paper's linear model V and A are rigid kinematics (l2, l3 only) and the
bending deflection D depends on the material and section only through κ = E h² / ρ, so (l2, l3, h) with E, ρ fixed
spans every response the paper's six variables can produce (see README).  The objective is the paper's Eq. 23-24,

    f = w_D f(D) + w_V f(V) + w_A f(A),   f(R) = RMS(R − R*) / (max R − min R)   (Eq. 18),

against the responses R* of a target design simulated by the same engine, so the global optimum is the target,
f = 0.  It is a least-squares problem (:attr:`residuals`): the output ``residuals`` holds, term after term (D, V, A),
w_R (R_i − R*_i) / ((max R − min R) sqrt(N)), whose sum of squares over one term is (w_R f(R))², so
f = Σ_R sqrt(Σ_i r_i²) and f = 0 exactly where every residual is 0.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.problem import DesignProblem, Variable
from mechopt.sim.flexible_slider_crank import ENGINES, MM, FlexibleSliderCrank, Response, normalised_error, simulate
from mechopt.sim.flexible_slider_crank.response import normalised_residuals

__all__ = ["DEFAULT_BOUNDS", "FlexibleSliderCrankProblem"]

#: The paper's Table 2 search intervals of the three variables (mm).
DEFAULT_BOUNDS = {"l2": (20.0, 80.0), "l3": (200.0, 500.0), "h": (1.0, 2.0)}
_LABELS = {"l2": "l2 (crank |OA|)", "l3": "l3 (rod |AB|)", "h": "h (rod thickness)"}

#: The paper's reference design (Table 1) with the thickness its near-zero solutions imply, κ = E h²/ρ = 62.544
#: m⁴/s² at the printed E = 71 GPa and ρ = 2660 kg/m³ (mm).
REFERENCE_MM = {"l2": 50.0, "l3": 350.0, "h": 1.53075}


class FlexibleSliderCrankProblem(DesignProblem):
    """Synthesis of the flexible slider-crank against a target design's V, A and D (paper 004, Section 3.1).

    Parameters
    ----------
    bounds : mapping of str to (float, float), optional
        Bounds (mm) of l2, l3 and h; default the paper's Table 2.
    target_mm : mapping of str to float, optional
        The target design (l2, l3, h in mm); default :data:`REFERENCE_MM`.
    weights : (float, float, float)
        Weights of f(D), f(V), f(A); default the paper's Eq. 24 (0.4, 0.3, 0.3).
    engine : str
        ``"modal"`` (default) or ``"exudyn"``.
    base : FlexibleSliderCrank, optional
        Everything else (E, ρ, width, slider mass, ω, damping, elements, modes, time grid); its l2, l3, h are
        replaced by each design's.
    """

    name = "flexible-slider-crank"
    constraints = ("buckling",)
    outputs = ("f", "f_D", "f_V", "f_A")
    objective = "f"
    # f is a weighted sum of RMS errors: a cone |δ| at the optimum, f² is smooth there (README: measured on a line)
    fit = "square"
    #: the output holding the weighted, normalised per-instant differences of D, V and A (module docstring)
    residuals = "residuals"
    #: 2: evaluate returns the residuals (samples stored by version 1 lack them)
    version = 2

    @property
    def fd_step(self) -> float:  # type: ignore[override]
        """Exudyn's Newton tolerance (1e-4) is noise to a difference; the modal model's fixed steps are smooth."""
        return 1e-3 if self.engine == "exudyn" else 1e-5

    def __init__(self, bounds: Mapping[str, tuple[float, float]] | None = None,
                 target_mm: Mapping[str, float] | None = None,
                 weights: tuple[float, float, float] = (0.4, 0.3, 0.3), engine: str = "modal",
                 base: FlexibleSliderCrank | None = None) -> None:
        bounds = dict(DEFAULT_BOUNDS if bounds is None else bounds)
        if set(bounds) != set(DEFAULT_BOUNDS):
            raise InputError(f"flexible slider-crank: variables {sorted(bounds)}; expected l2, l3, h")
        self.variables = tuple(Variable(k, *bounds[k], unit="mm", label=_LABELS[k]) for k in ("l2", "l3", "h"))
        target = dict(REFERENCE_MM if target_mm is None else target_mm)
        if set(target) != set(DEFAULT_BOUNDS):
            raise InputError(f"flexible slider-crank: target {sorted(target)}; expected l2, l3, h (mm)")
        self.target_mm = {k: float(target[k]) for k in ("l2", "l3", "h")}
        # The target's own responses are the reference: the global optimum is known, f = 0 there.
        self.f_min = 0.0
        self.x_min = np.array([[self.target_mm[k] for k in ("l2", "l3", "h")]])
        if len(weights) != 3 or any(not np.isfinite(w) or w < 0 for w in weights) or sum(weights) <= 0:
            raise InputError(f"flexible slider-crank: weights {weights!r}; expected three numbers >= 0 (D, V, A)")
        self.weights = tuple(float(w) for w in weights)
        if engine not in ENGINES:
            raise InputError(f"flexible slider-crank: engine = {engine!r}; expected one of {', '.join(ENGINES)}")
        self.engine = engine
        self.base = FlexibleSliderCrank() if base is None else base
        self._target: Response | None = None

    # --- constraints ----------------------------------------------------------------------------------------------

    def margins(self, X: np.ndarray) -> np.ndarray:
        """Buckling margin 1 − N_max / P_E (dimensionless) of designs X (n, 3) in mm.

        N_max is the largest compressive force the slider's inertia puts on the rod over a crank turn (rigid
        kinematics, sampled every degree) and P_E = π² E I / l3² the rod's Euler load.  Beyond it the rod buckles:
        the geometrically exact Exudyn engine shows deflections of ~100 mm (l2 = 76, l3 = 445, h = 1.0 mm) where
        the linear model, which has no axial-force stiffness, stays below 1 mm (README).
        """
        X = np.atleast_2d(np.asarray(X, dtype=float))
        out = np.empty((X.shape[0], 1))
        b = self.base
        theta = np.linspace(0.0, 2.0 * np.pi, 361)
        c, sn = np.cos(theta), np.sin(theta)
        # Vectorised over designs in chunks (search grids have millions): the slider's acceleration at constant ω,
        # x = r cos θ + s, s = sqrt(l² − r² sin² θ): x'' = ω² (−r cos θ − r² cos 2θ / s − r⁴ sin²θ cos²θ / s³).
        for lo in range(0, X.shape[0], 20_000):
            r, l, h = (X[lo : lo + 20_000, k : k + 1] * MM for k in range(3))
            s_ = np.sqrt(np.maximum(l * l - (r * sn) ** 2, 1e-300))
            acc = b.omega**2 * (-r * c - r * r * (c * c - sn * sn) / s_ - r**4 * (sn * c) ** 2 / s_**3)
            n_max = b.slider_mass * np.maximum(acc.max(axis=1), 0.0)
            p_e = np.pi**2 * b.E * b.a * h[:, 0] ** 3 / 12.0 / l[:, 0] ** 2
            out[lo : lo + 20_000, 0] = 1.0 - n_max / p_e
        return out

    def sampleable(self, X: np.ndarray) -> np.ndarray:
        """Every design in the box: the modal model simulates buckled rods too (its lines may run beyond)."""
        return self.in_box(X)

    # --- simulation -----------------------------------------------------------------------------------------------

    def parameters(self, x: np.ndarray) -> FlexibleSliderCrank:
        """The simulation settings of design ``x`` = (l2, l3, h) in mm."""
        l2, l3, h = (float(v) for v in np.ravel(x))
        return self.base.with_(l2=l2 * MM, l3=l3 * MM, h=h * MM)

    def response(self, x: np.ndarray) -> Response:
        """Simulate design ``x`` (mm) with the problem's engine."""
        return simulate(self.parameters(x), self.engine)

    def target(self) -> Response:
        """The target design's responses (simulated once, then kept)."""
        if self._target is None:
            self._target = self.response(np.array([self.target_mm[k] for k in ("l2", "l3", "h")]))
        return self._target

    def errors(self, r: Response) -> dict[str, float]:
        """The paper's normalised errors of a response against the target, and their weighted sum."""
        ref = self.target()
        f_d, f_v, f_a = (normalised_error(getattr(r, k), getattr(ref, k)) for k in ("D", "V", "A"))
        w_d, w_v, w_a = self.weights
        return {"f": w_d * f_d + w_v * f_v + w_a * f_a, "f_D": f_d, "f_V": f_v, "f_A": f_a}

    def response_residuals(self, r: Response) -> np.ndarray:
        """The residuals of a response against the target: w_R (R − R*) / (range R sqrt(N)) for R = D, V, A in turn.

        The square root of one term's sum of squares is w_R f(R), so their sum is f of :meth:`errors`.
        """
        ref = self.target()
        return np.concatenate([w * normalised_residuals(getattr(r, k), getattr(ref, k))
                               for w, k in zip(self.weights, ("D", "V", "A"), strict=True)])

    def evaluate(self, x: np.ndarray) -> dict[str, Any]:
        """Simulate design ``x`` = (l2, l3, h) in mm; returns f, f_D, f_V, f_A, the rod's peak deflection (mm) and
        the residuals (:meth:`response_residuals`, a list)."""
        r = self.response(x)
        out: dict[str, Any] = self.errors(r)
        out["D_peak_mm"] = float(np.max(np.abs(r.D)) / MM)
        out["residuals"] = self.response_residuals(r).tolist()
        return out

    # --- declaration ---------------------------------------------------------------------------------------------

    def settings(self) -> dict[str, Any]:
        """Everything that changes an output: engine, material, section width, slider, drive, damping, grids."""
        return {"engine": self.engine, "target_mm": self.target_mm, "weights_D_V_A": list(self.weights),
                "mechanism": self.base.as_dict()}

    def figures(self, designs: Mapping[str, np.ndarray], out: Path) -> dict[str, Path]:
        """Response curves of each design against the target, and the first design's rod animated over a turn."""
        from mechopt.sim.flexible_slider_crank.figures import animate_rod, plot_responses

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        made: dict[str, Path] = {}
        ref = self.target()
        for i, (label, x) in enumerate(designs.items()):
            r = self.response(x)
            caption = f"Slider velocity, acceleration and rod mid-point deflection: {label} against the target"
            made[caption] = plot_responses(r, ref, label, self.describe(x), out / f"flexible_responses_{label}.png")
            if i == 0:
                made[f"Rod deflection over one crank turn ({label})"] = animate_rod(
                    r, self.parameters(x), label, out / f"flexible_rod_{label}.gif")
        return made
