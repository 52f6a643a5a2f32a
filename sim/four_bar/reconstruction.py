"""Reconstruction of an unpublished four-bar from its reduced inertia and load tables at the motor shaft.

For a four-bar with O at the origin, known link lengths and a light coupler, the inertia seen at the motor is
J(θ) = J0 + I_r (dψ/dθ)², which depends on the unknown rocker pivot C only through ψ(θ).  For a given C the model is
linear in (J0, I_r), so the fit is a variable projection: a nonlinear least-squares problem in (x_C, y_C) alone,
solved from many random starts on both assembly branches.  The static motor torque T_l(θ) then gives, by virtual
work, the design-independent rocker load M_r(ψ) = T_l(θ) · dθ/dψ.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from mechopt.errors import StudyError
from mechopt.sim.four_bar.kinematics import crank_angle, rocker_angle
from mechopt.sim.four_bar.load import RockerLoad


@dataclass(frozen=True)
class MotorTable:
    """Load and inertia of a mechanism as seen at the motor shaft, per crank angle.

    Attributes
    ----------
    theta : (n,) ndarray
        Crank angles θ (rad).
    load_torque : (n,) ndarray
        Static motor torque T_l(θ) holding the mechanism at θ (N·m).
    inertia : (n,) ndarray
        Reduced inertia J(θ) at the motor shaft (kg·m²).
    """

    theta: np.ndarray
    load_torque: np.ndarray
    inertia: np.ndarray


@dataclass(frozen=True)
class Reconstruction:
    """Rocker pivot, inertias, stroke and rocker load recovered from a :class:`MotorTable`.

    Attributes
    ----------
    pivot_c : (float, float)
        Rocker ground pivot C (mm).
    j0, i_r : float
        Inertia on the crank and of the rocker about C (kg·m²).
    forward_branch : int
        Circle-intersection branch of ψ(θ) that fits the table.
    inverse_branch : int
        Branch of Eq. 4 (θ from ψ) giving the same assembly (−1: θ1).
    psi_start, psi_end : float
        Output angles of the original design at the stroke's start and end crank angles (rad).
    load : RockerLoad
        Rocker load M_r(ψ) (N·m).
    load_table : (2, n) ndarray
        The tabulated (ψ rad, M_r N·m) behind ``load``.
    relative_rms_misfit : float
        RMS of (J_model − J)/J over the table.
    n_starts : int
        Random starts used per branch.
    """

    pivot_c: tuple[float, float]
    j0: float
    i_r: float
    forward_branch: int
    inverse_branch: int
    psi_start: float
    psi_end: float
    load: RockerLoad
    load_table: np.ndarray
    relative_rms_misfit: float
    n_starts: int

    def summary(self) -> dict:
        """JSON-able numbers of the reconstruction (mm, deg, kg·m²)."""
        return {
            "pivot_c_mm": [round(self.pivot_c[0], 4), round(self.pivot_c[1], 4)],
            "j0_kgm2": self.j0,
            "i_r_kgm2": self.i_r,
            "psi_start_deg": float(np.degrees(self.psi_start)),
            "psi_end_deg": float(np.degrees(self.psi_end)),
            "load_table_psi_deg": [float(np.degrees(self.load_table[0].min())),
                                   float(np.degrees(self.load_table[0].max()))],
            "relative_rms_misfit": self.relative_rms_misfit,
            "n_starts": self.n_starts,
        }


def read_motor_table(path: Path) -> MotorTable:
    """Read a CSV with columns ``theta_rad``, ``load_torque_Nm``, ``inertia_kgm2``.

    Raises
    ------
    StudyError
        If the file is missing, a column is absent or a value is not a finite number.
    """
    path = Path(path)
    if not path.is_file():
        raise StudyError(f"motor table {path} not found")
    with path.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    cols = ("theta_rad", "load_torque_Nm", "inertia_kgm2")
    if not rows or any(c not in rows[0] for c in cols):
        raise StudyError(f"motor table {path.name}: expected columns {', '.join(cols)}")
    try:
        data = np.array([[float(r[c]) for c in cols] for r in rows])
    except (TypeError, ValueError) as exc:
        raise StudyError(f"motor table {path.name}: non-numeric value ({exc})") from None
    if not np.all(np.isfinite(data)) or len(data) < 8:
        raise StudyError(f"motor table {path.name}: needs at least 8 rows of finite numbers")
    return MotorTable(data[:, 0], data[:, 1], data[:, 2])


def _psi_and_ratio(design, pivot, theta, branch):
    psi, ratio = rocker_angle(design, pivot, theta, branch)
    return psi, ratio


def _inertia_residual(pivot, design, table: MotorTable, branch):
    """Relative residuals of J with (J0, I_r) eliminated by linear least squares; None if C does not assemble."""
    _, ratio = _psi_and_ratio(design, pivot, table.theta, branch)
    if not np.all(np.isfinite(ratio)):
        return None, None
    basis = np.column_stack([np.ones_like(ratio), ratio * ratio]) / table.inertia[:, None]
    coef, *_ = np.linalg.lstsq(basis, np.ones_like(ratio), rcond=None)
    return basis @ coef - 1.0, coef


def _assembles(pivot, design, theta) -> bool:
    oa, ab, bc = design
    a = np.stack([oa * np.cos(theta), oa * np.sin(theta)], axis=1)
    dist = np.hypot(a[:, 0] - pivot[0], a[:, 1] - pivot[1])
    return bool(np.all((dist <= ab + bc) & (dist >= abs(bc - ab))))


def fit_pivot(
    table: MotorTable,
    design: tuple[float, float, float],
    n_starts: int = 400,
    seed: int = 0,
    box_mm: float = 600.0,
    n_polish: int = 12,
) -> tuple[tuple[float, float], float, float, int, float]:
    """Fit the rocker pivot C and the inertias (J0, I_r) to the table's J(θ).

    Parameters
    ----------
    table : MotorTable
        The motor-side table of the original design.
    design : (3,) tuple
        |OA|, |AB|, |BC| of the original (mm).
    n_starts : int
        Random starts per assembly branch (uniform in the square of half-width ``box_mm`` around O, kept where the
        original assembles over the whole table).
    seed : int
        Seed of the starts.
    box_mm : float
        Half-width of the square of starts (mm).
    n_polish : int
        Starts per branch, the best screened ones, polished by Levenberg–Marquardt.

    Returns
    -------
    pivot_c, j0, i_r, branch, misfit
        C (mm), inertias (kg·m²), the forward branch, RMS relative misfit.
    """
    rng = np.random.default_rng(seed)
    best = None
    for branch in (-1, 1):
        starts = []
        while len(starts) < n_starts:
            cand = rng.uniform(-box_mm, box_mm, size=(4 * n_starts, 2))
            starts.extend(c for c in cand if _assembles(c, design, table.theta))
        # Screen every start by its misfit and polish the most promising ones: the misfit landscape is smooth and
        # the polished starts all land on the same minimum, so polishing all of them would only cost time.
        screened = []
        for start in starts[:n_starts]:
            r, _ = _inertia_residual(start, design, table, branch)
            if r is not None:
                screened.append((float(np.mean(r * r)), tuple(start)))
        screened.sort()
        for _, start in screened[:n_polish]:

            def fun(p, branch=branch):
                r, _ = _inertia_residual(p, design, table, branch)
                # A pivot that does not assemble gets a flat, large residual: the solver backs off its step.
                return np.full(table.theta.size, 1e3) if r is None else r

            sol = least_squares(fun, start, method="lm", xtol=1e-12, ftol=1e-12, max_nfev=400)
            r, coef = _inertia_residual(sol.x, design, table, branch)
            if r is None or np.any(coef < 0):
                continue
            misfit = float(np.sqrt(np.mean(r * r)))
            if best is None or misfit < best[4]:
                best = ((float(sol.x[0]), float(sol.x[1])), float(coef[0]), float(coef[1]), branch, misfit)
    if best is None:
        raise StudyError("reconstruction failed: no rocker pivot assembles the original over the table")
    return best


def reconstruct(
    table: MotorTable,
    design: tuple[float, float, float],
    theta_start: float,
    theta_end: float,
    n_starts: int = 400,
    seed: int = 0,
) -> Reconstruction:
    """Reconstruct pivot, inertias, stroke angles and rocker load from a motor table.

    Parameters
    ----------
    table : MotorTable
        Load and inertia of the original design at the motor shaft.
    design : (3,) tuple
        |OA|, |AB|, |BC| of the original (mm).
    theta_start, theta_end : float
        Crank angles of the original at the start and end of the stroke (rad).
    n_starts : int
        Random starts per assembly branch of the pivot fit.
    seed : int
        Seed of the starts.

    Returns
    -------
    Reconstruction
    """
    pivot, j0, i_r, branch, misfit = fit_pivot(table, design, n_starts, seed)
    psi_table, ratio = rocker_angle(design, pivot, table.theta, branch)
    psi_table = np.unwrap(psi_table)
    psi_start, psi_end = rocker_angle(design, pivot, np.array([theta_start, theta_end]), branch)[0]
    psi_start = _near(psi_start, psi_table)
    psi_end = _near(psi_end, psi_table)
    inverse = None
    for b in (-1, 1):
        th = float(crank_angle(design, pivot, psi_start, b)[0][0])
        if np.isfinite(th) and abs(np.angle(np.exp(1j * (th - theta_start)))) < 1e-7:
            inverse = b
    if inverse is None:
        raise StudyError("reconstruction failed: no branch of Eq. 4 returns the original's start angle")
    # Virtual work: T_l δθ = M_r δψ.
    load_values = table.load_torque / ratio
    load = RockerLoad.from_table(psi_table, load_values)
    return Reconstruction(
        pivot_c=pivot, j0=j0, i_r=i_r, forward_branch=branch, inverse_branch=inverse,
        psi_start=float(psi_start), psi_end=float(psi_end), load=load,
        load_table=np.vstack([psi_table, load_values]), relative_rms_misfit=misfit, n_starts=n_starts,
    )


def _near(angle: float, reference: np.ndarray) -> float:
    """The representative of ``angle`` (mod 2π) closest to the reference angles."""
    mid = float(np.mean(reference))
    return float(mid + np.angle(np.exp(1j * (angle - mid))))
