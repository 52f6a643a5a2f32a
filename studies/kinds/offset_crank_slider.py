"""Paper 001's study: an offset crank-slider with a desired stroke and time ratio (Powell + penalties in the paper).

Design variables hn = h/r2 and r3n = r3/r2 (crank r2 fixed).  Objective (paper Eq. 11)

    F = δ1 (Sn − Sn_des)² + δ2 (TR − TR_des)²,   Sn = S/r2 (Eq. 2), TR (Eqs. 3–6),

and the paper's functional constraints (Eqs. 12–19) as hard constraints (margins), not penalties:
45° <= TA_min <= 90°, 90° <= TA_max <= 135°, 0.05 <= Fc3 = (r3n − 1)² − hn² <= 10.  The transmission-angle extremes
are the exact ones over a crank revolution, TA_min/max = 90° + asin((hn ∓ 1)/r3n): they reproduce the paper's
reported ranges, its printed Eqs. 9–10 do not (see studies/offset_crank_slider/README.md).  The paper prints
neither its weights nor its penalty constants: δ1 = δ2 = 1 by default.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InfeasibleDesignError, StudyError
from mechopt.optimize.problem import DesignProblem, Variable, as_design_array
from mechopt.sim.slider_crank.kinematics import transmission_extremes
from mechopt.sim.slider_crank.limits import stroke, time_ratio
from mechopt.studies.kinds.slider_crank_common import check_options, variables_from_study
from mechopt.studies.study_file import StudyFile

#: Constraint columns of :meth:`OffsetCrankSliderProblem.margins` (deg, deg, deg, deg, –, –).
CONSTRAINTS = ("ta_min_above_deg", "ta_min_below_deg", "ta_max_above_deg", "ta_max_below_deg",
               "fc3_above", "fc3_below")


def paper_eq9_10(hn: np.ndarray | float, r3n: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """TA_min, TA_max (deg) by the paper's printed Eqs. 7–10, kept to show that they do not reproduce its numbers.

    β = atan(1/r3n), α = asin(hn/√(1 + r3n²)), TA_min = 90° − (β − α), TA_max = 90° + β + α.
    """
    hn, r3n = np.asarray(hn, dtype=float), np.asarray(r3n, dtype=float)
    beta = np.degrees(np.arctan(1.0 / r3n))
    alpha = np.degrees(np.arcsin(hn / np.sqrt(1.0 + r3n**2)))
    return 90.0 - (beta - alpha), 90.0 + beta + alpha


def regression_design(sn: float, tr: float) -> tuple[float, float]:
    """(hn, r3n) of the paper's fitted models Eqs. 22–23 at stroke Sn and time ratio TR (coefficients as printed)."""
    a1 = (-78.17080688477, 42.1585998535, 48.89712905884, -2.0545334816, -1.86831796169, -22.46410369873)
    a2 = (-230.653076172, 144.45611572266, 124.905418396, -15.91238498688, -6.7251915932, -55.66365814209)
    terms = (1.0, sn, tr, sn * sn, tr * tr, sn * tr)
    return float(np.dot(a1, terms)), float(np.dot(a2, terms))


class OffsetCrankSliderProblem(DesignProblem):
    """Offset crank-slider with a desired stroke and time ratio (paper 001).

    Parameters
    ----------
    variables : tuple of Variable
        ``hn`` and ``r3n`` with their bounds.
    r2_mm : float
        Crank length r2 (mm).
    stroke_mm, time_ratio : float
        Desired stroke S (mm) and time ratio TR.
    weights : (float, float)
        δ1, δ2.
    ta_min_range_deg, ta_max_range_deg, fc3_range : (float, float)
        Allowed ranges of TA_min, TA_max (deg) and of Fc3 = (r3n − 1)² − hn².
    """

    name = "offset-crank-slider"
    outputs = ("objective", "stroke_n", "time_ratio", "stroke_mm", "ta_min_deg", "ta_max_deg")
    objective = "objective"
    fit = "value"
    constraints = CONSTRAINTS

    def __init__(self, variables: tuple[Variable, ...], r2_mm: float = 100.0, stroke_mm: float = 250.0,
                 time_ratio: float = 1.5, weights: tuple[float, float] = (1.0, 1.0),
                 ta_min_range_deg: tuple[float, float] = (45.0, 90.0),
                 ta_max_range_deg: tuple[float, float] = (90.0, 135.0),
                 fc3_range: tuple[float, float] = (0.05, 10.0)) -> None:
        self.variables = tuple(variables)
        self.r2_mm = float(r2_mm)
        self.stroke_mm = float(stroke_mm)
        self.time_ratio = float(time_ratio)
        self.weights = (float(weights[0]), float(weights[1]))
        self.ta_min_range_deg = tuple(map(float, ta_min_range_deg))
        self.ta_max_range_deg = tuple(map(float, ta_max_range_deg))
        self.fc3_range = tuple(map(float, fc3_range))

    @property
    def stroke_n_target(self) -> float:
        """Desired normalised stroke Sn_des = S/r2."""
        return self.stroke_mm / self.r2_mm

    def settings(self) -> dict[str, Any]:
        return {"r2_mm": self.r2_mm, "stroke_mm": self.stroke_mm, "time_ratio": self.time_ratio,
                "weights": list(self.weights), "ta_min_range_deg": list(self.ta_min_range_deg),
                "ta_max_range_deg": list(self.ta_max_range_deg), "fc3_range": list(self.fc3_range)}

    def quantities(self, X: np.ndarray) -> dict[str, np.ndarray]:
        """Sn, TR, TA_min, TA_max (deg), Fc3 and the objective of designs (n, 2), vectorised; NaN where the crank
        cannot turn fully."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        hn, r3n = X[:, 0], X[:, 1]
        sn = stroke(1.0, r3n, hn)
        tr = time_ratio(1.0, r3n, hn)
        ta_min, ta_max = transmission_extremes(1.0, r3n, hn)
        d1, d2 = self.weights
        f = d1 * (sn - self.stroke_n_target) ** 2 + d2 * (tr - self.time_ratio) ** 2
        return {"stroke_n": sn, "time_ratio": tr, "ta_min_deg": ta_min, "ta_max_deg": ta_max,
                "fc3": (r3n - 1.0) ** 2 - hn**2, "objective": f}

    def margins(self, X: np.ndarray) -> np.ndarray:
        q = self.quantities(X)
        (a, b), (c, d), (e, f) = self.ta_min_range_deg, self.ta_max_range_deg, self.fc3_range
        m = np.column_stack([q["ta_min_deg"] - a, b - q["ta_min_deg"], q["ta_max_deg"] - c, d - q["ta_max_deg"],
                             q["fc3"] - e, f - q["fc3"]])
        # Where the crank cannot turn fully the angles are undefined: violated.
        return np.nan_to_num(m, nan=-90.0)

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        hn, r3n = (float(v) for v in as_design_array(x, 2, "design")[0])
        fc3 = (r3n - 1.0) ** 2 - hn * hn
        if not fc3 > 0:
            raise InfeasibleDesignError(f"{self.describe(x)}: the crank cannot turn fully ((r3n − 1)² − hn² = "
                                        f"{fc3:.4g} <= 0)")
        # Scalar closed forms (the same as :meth:`quantities`, which a test checks): a few microseconds.
        sn = math.sqrt((r3n + 1.0) ** 2 - hn * hn) - math.sqrt(fc3)
        psi = abs(math.asin(hn / (r3n - 1.0)) - math.asin(hn / (r3n + 1.0)))
        tr = (math.pi + psi) / (math.pi - psi)
        d1, d2 = self.weights
        return {"objective": d1 * (sn - self.stroke_n_target) ** 2 + d2 * (tr - self.time_ratio) ** 2,
                "stroke_n": sn, "time_ratio": tr, "stroke_mm": sn * self.r2_mm,
                "ta_min_deg": 90.0 + math.degrees(math.asin((hn - 1.0) / r3n)),
                "ta_max_deg": 90.0 + math.degrees(math.asin((hn + 1.0) / r3n)), "fc3": fc3}

    def mm_design(self, x: np.ndarray) -> np.ndarray:
        """(r, l, h) in mm of a design (hn, r3n)."""
        hn, r3n = np.ravel(x)
        return np.array([self.r2_mm, r3n * self.r2_mm, hn * self.r2_mm])

    def figures(self, designs: Mapping[str, np.ndarray], out: Path) -> dict[str, Path]:
        from mechopt.sim.slider_crank.figures import cycle_animation, limit_positions_figure

        mm = {name: self.mm_design(x) for name, x in designs.items()}
        figs = {"Mechanisms at their limit positions": limit_positions_figure(mm, Path(out) / "limit_positions.png")}
        for name, d in mm.items():
            figs[f"One crank revolution of the {name} design"] = cycle_animation(d, Path(out) / f"cycle_{name}.gif",
                                                                               title=f"{name} design")
        return figs


def problem_from_study(study: StudyFile, options: dict[str, Any]) -> OffsetCrankSliderProblem:
    """The problem of a study file of kind ``offset-crank-slider``.

    Sections read: ``[variables]`` (hn, r3n bounds), ``[mechanism]`` (``r2_mm``), ``[targets]`` (``stroke_mm``,
    ``time_ratio``), ``[objective]`` (``weight_stroke``, ``weight_time_ratio``), ``[constraints]``
    (``ta_min_deg``, ``ta_max_deg``, ``fc3``: [lower, upper] each).

    Raises
    ------
    StudyError
        A malformed key, a target no slider-crank can reach (stroke below 2 r2, time ratio below 1), or bounds
        holding no feasible design.
    """
    check_options(study, options)
    variables = variables_from_study(study, (("hn", "", "h/r2"), ("r3n", "", "r3/r2")),
                                     {"hn": (0.1, 3.0), "r3n": (1.05, 10.0)})
    mech = study.table("mechanism", allowed=("r2_mm",), required=False)
    r2 = study.number(mech, "r2_mm", "mechanism", default=100.0, positive=True)
    tg = study.table("targets", allowed=("stroke_mm", "time_ratio"))
    s_mm = study.number(tg, "stroke_mm", "targets", positive=True)
    tr = study.number(tg, "time_ratio", "targets")
    if s_mm <= 2.0 * r2:
        raise StudyError(f"{study.where}: targets.stroke_mm = {s_mm:g} mm is unreachable: every slider-crank whose "
                         f"crank turns fully has a stroke > 2 r2 = {2 * r2:g} mm")
    if tr < 1.0:
        raise StudyError(f"{study.where}: targets.time_ratio = {tr:g} is unreachable: the slow stroke over the fast "
                         "one is >= 1")
    obj = study.table("objective", allowed=("weight_stroke", "weight_time_ratio"), required=False)
    weights = (study.number(obj, "weight_stroke", "objective", default=1.0, minimum=0.0),
               study.number(obj, "weight_time_ratio", "objective", default=1.0, minimum=0.0))
    if weights[0] + weights[1] <= 0:
        raise StudyError(f"{study.where}: objective weights are both zero; expected at least one > 0")
    con = study.table("constraints", allowed=("ta_min_deg", "ta_max_deg", "fc3"), required=False)
    ranges = []
    for key, default in (("ta_min_deg", [45.0, 90.0]), ("ta_max_deg", [90.0, 135.0]), ("fc3", [0.05, 10.0])):
        lo, hi = study.numbers(con, key, "constraints", length=2, default=default)
        if not lo < hi:
            raise StudyError(f"{study.where}: key constraints.{key} = [{lo:g}, {hi:g}] must satisfy lower < upper")
        ranges.append((lo, hi))
    problem = OffsetCrankSliderProblem(variables, r2, s_mm, tr, weights, *ranges)
    _require_feasible(problem, study)
    return problem


def _require_feasible(problem: DesignProblem, study: StudyFile, n: int = 241) -> None:
    """Raise a one-line StudyError when a dense grid over the bounds holds no feasible design."""
    b = problem.bounds
    g = np.meshgrid(*(np.linspace(lo, hi, n) for lo, hi in b), indexing="ij")
    if not problem.feasible(np.column_stack([v.ravel() for v in g])).any():
        box = ", ".join(f"{v.name} in [{v.lower:g}, {v.upper:g}]" for v in problem.variables)
        raise StudyError(f"{study.where}: no feasible design: no point of a {n}x{n} grid over {box} satisfies the "
                         f"constraints {list(problem.constraints)}")
