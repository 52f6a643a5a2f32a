"""Paper 003's study: an in-line slider-crank loading a spring, whose effort must follow a desired curve F_d.

Design (l2, l3) in mm (crank, rod), offset 0; effort F(θ) = k x(θ) with x = l2 cos θ + √(l3² − l2² sin² θ) (the
paper's Table 6; its Eq. 16 prints a sign error under the root) at the angles of its code, t = 0:0.1:2π; objective
the mean square error to F_d (N²), the paper's cost function.  F_d is the reconstruction of
:mod:`.rowing_reconstruction`, read from the study's data file.  Constraint: the crank turns fully, l3 − l2 > 0
(the paper's L2 < L3).
"""

from __future__ import annotations

import csv
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InfeasibleDesignError, StudyError
from mechopt.optimize.problem import DesignProblem, Variable, as_design_array
from mechopt.studies.kinds.slider_crank_common import check_options, variables_from_study
from mechopt.studies.study_file import StudyFile

CONSTRAINTS = ("rod_minus_crank_mm",)


class RowingProblem(DesignProblem):
    """Spring-loaded in-line slider-crank of a rowing machine (paper 003).

    Parameters
    ----------
    variables : tuple of Variable
        ``l2`` and ``l3`` (mm) with their bounds.
    theta : (n,) ndarray
        Crank angles of the cost function (rad).
    desired : (n,) ndarray
        Desired effort F_d at those angles (N).
    k : float
        Spring stiffness (N/mm).
    """

    name = "rowing"
    outputs = ("mse_N2", "rms_error_N", "max_error_N", "f_max_N", "f_min_N")
    objective = "mse_N2"
    fit = "value"
    constraints = CONSTRAINTS
    #: The mean square error is the sum of squares of (F_d − F) / √n: a least-squares problem.
    residuals = "residuals"
    version = 2

    def __init__(self, variables: tuple[Variable, ...], theta: np.ndarray, desired: np.ndarray, k: float = 244.0
                 ) -> None:
        self.variables = tuple(variables)
        self.theta = np.asarray(theta, dtype=float)
        self.desired = np.asarray(desired, dtype=float)
        self.k = float(k)
        self._cos = np.cos(self.theta)
        self._sin2 = np.sin(self.theta) ** 2

    def settings(self) -> dict[str, Any]:
        return {"k_N_per_mm": self.k, "theta_rad": self.theta.round(12).tolist(),
                "desired_N": self.desired.round(9).tolist()}

    def margins(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, dtype=float))
        return (X[:, 1] - X[:, 0])[:, None]

    def effort(self, x: np.ndarray) -> np.ndarray:
        """Effort F(θ) = k x(θ) (N) of a design (l2, l3) in mm at the study's angles."""
        l2, l3 = np.ravel(x)
        return self.k * (l2 * self._cos + np.sqrt(l3 * l3 - l2 * l2 * self._sin2))

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        l2, l3 = (float(v) for v in as_design_array(x, 2, "design")[0])
        if not (l2 > 0 and l3 > l2):
            raise InfeasibleDesignError(f"{self.describe(np.array([l2, l3]))}: the crank cannot turn fully "
                                        "(expected 0 < l2 < l3)")
        f = self.effort(np.array([l2, l3]))
        err = self.desired - f
        mse = float(np.dot(err, err) / err.size)
        return {"mse_N2": mse, "rms_error_N": float(np.sqrt(mse)), "max_error_N": float(np.max(np.abs(err))),
                "f_max_N": float(f.max()), "f_min_N": float(f.min()),
                "residuals": (err / np.sqrt(err.size)).tolist()}

    def figures(self, designs: Mapping[str, np.ndarray], out: Path) -> dict[str, Path]:
        from mechopt.sim.slider_crank.figures import cycle_animation, effort_figure, limit_positions_figure

        out = Path(out)
        mm = {name: np.array([float(x[0]), float(x[1]), 0.0]) for name, x in designs.items()}
        curves = {f"{name} (l2={x[0]:.3f}, l3={x[1]:.3f} mm)": self.effort(x) for name, x in designs.items()}
        figs = {"Spring effort against the desired effort": effort_figure(
                    self.theta, curves, self.desired, out / "effort.png",
                    title="Rowing slider-crank: spring effort F = k x against the desired F_d"),
                "Mechanisms at their limit positions": limit_positions_figure(mm, out / "limit_positions.png")}
        for name, d in mm.items():
            figs[f"One crank revolution of the {name} design"] = cycle_animation(d, out / f"cycle_{name}.gif",
                                                                               title=f"{name} design")
        return figs


def read_desired(path: Path, where: str) -> tuple[np.ndarray, np.ndarray]:
    """Angles (rad) and F_d (N) from a CSV ``theta_rad,fd_kN`` (one-line StudyError when malformed)."""
    try:
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
    except OSError as exc:
        raise StudyError(f"{where}: cannot read {path}: {exc}") from None
    if not rows or [c.strip() for c in rows[0]] != ["theta_rad", "fd_kN"]:
        raise StudyError(f"{where}: {Path(path).name}: expected the header 'theta_rad,fd_kN'")
    try:
        data = np.array([[float(c) for c in row] for row in rows[1:] if row], dtype=float)
    except ValueError:
        raise StudyError(f"{where}: {Path(path).name}: every row must be two numbers") from None
    if data.ndim != 2 or data.shape[1] != 2 or len(data) < 3 or not np.all(np.isfinite(data)):
        raise StudyError(f"{where}: {Path(path).name}: expected at least 3 rows of two finite numbers")
    return data[:, 0], data[:, 1] * 1000.0


def problem_from_study(study: StudyFile, options: dict[str, Any]) -> RowingProblem:
    """The problem of a study file of kind ``rowing``.

    Sections read: ``[variables]`` (l2, l3 bounds in mm), ``[mechanism]`` (``spring_k_N_per_mm``), ``[effort]``
    (``desired``: the CSV of F_d).

    Raises
    ------
    StudyError
        A malformed key or data file, bounds holding no design whose crank turns (l3 > l2), or a desired effort
        outside what a spring pushed by a slider-crank can give (F_d <= 0 somewhere).
    """
    check_options(study, options)
    variables = variables_from_study(study, (("l2", "mm", "L2"), ("l3", "mm", "L3")),
                                     {"l2": (1.0, 10.0), "l3": (11.0, 20.0)})
    mech = study.table("mechanism", allowed=("spring_k_N_per_mm",), required=False)
    k = study.number(mech, "spring_k_N_per_mm", "mechanism", default=244.0, positive=True)
    eff = study.table("effort", allowed=("desired",))
    theta, desired = read_desired(study.data_path(study.string(eff, "desired", "effort"), "effort.desired"),
                                  study.where)
    l2, l3 = variables
    if l3.upper <= l2.lower:
        raise StudyError(f"{study.where}: no feasible design: l3 <= {l3.upper:g} mm never exceeds l2 >= "
                         f"{l2.lower:g} mm, so no crank turns fully")
    if np.min(desired) <= 0:
        raise StudyError(f"{study.where}: desired effort {np.min(desired):g} N <= 0 is unreachable: a compressed "
                         "spring on a slider at x > 0 pushes with F = k x > 0")
    return RowingProblem(variables, theta, desired, k)
