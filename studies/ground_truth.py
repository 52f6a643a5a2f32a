"""Ground truth: the true optimum of a study by dense brute force of the analytic engine, then a local polish.

The paper could not know its true optimum (10 million CAD runs); with the analytic engine (numba, ~10⁵ designs/s) a
dense grid over the whole region is affordable.  The grid's best feasible design is refined on a finer local grid and
polished by SLSQP with the feasibility margins as inequality constraints.  The result is cached in a JSON file keyed
by the study's settings, so comparisons do not recompute it.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from mechopt.sim.fourbar.analytic import analytic_batch
from mechopt.sim.fourbar.feasibility import check_feasibility, constraint_margins
from scipy.optimize import minimize

from .definition import Study


@dataclass
class GroundTruth:
    """The true optimum of a study over its region.

    Attributes
    ----------
    x : list of float
        Optimal design (|OA|, |AB|, |BC|) in mm.
    fun : float
        Its T_RMS (N·m), analytic engine.
    grid_x, grid_fun : list of float, float
        Best point of the coarse grid and its T_RMS.
    step_mm : float
        Spacing of the coarse grid (mm).
    n_evaluated, n_feasible : int
        Designs on the coarse grid, and how many of them are feasible.
    margins : dict
        Constraint margins at ``x``.
    wall_time_s : float
        Time to compute it (s).
    key : str
        Hash of the study settings it belongs to.
    """

    x: list[float]
    fun: float
    grid_x: list[float]
    grid_fun: float
    step_mm: float
    n_evaluated: int
    n_feasible: int
    margins: dict
    wall_time_s: float
    key: str


def study_key(study: Study, step_mm: float) -> str:
    """Hash of everything the ground truth depends on: the study file, its data and the grid step."""
    h = hashlib.sha256(study.path.read_bytes())
    m = study.mechanism
    h.update(json.dumps([m.pivot_c, m.j0, m.i_r, m.psi_start, m.psi_end, step_mm]).encode())
    return h.hexdigest()[:16]


def evaluate_grid(study: Study, axes: list[np.ndarray], chunk: int = 400_000) -> tuple[np.ndarray, float, int, int]:
    """Best feasible design on the tensor grid ``axes`` (mm), its T_RMS, the designs evaluated and feasible."""
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    best_x, best_f, n_feasible = None, np.inf, 0
    for lo in range(0, mesh.shape[0], chunk):
        block = mesh[lo : lo + chunk]
        ok = check_feasibility(block, study.mechanism).feasible
        n_feasible += int(ok.sum())
        if not ok.any():
            continue
        t_rms, _ = analytic_batch(block[ok], study.mechanism, check=False)
        i = int(np.nanargmin(t_rms))
        if t_rms[i] < best_f:
            best_x, best_f = block[ok][i], float(t_rms[i])
    return best_x, best_f, mesh.shape[0], n_feasible


def polish(study: Study, x0: np.ndarray) -> tuple[np.ndarray, float]:
    """SLSQP from ``x0`` on the analytic T_RMS, with the feasibility margins as constraints and the region's bounds."""
    mech = study.mechanism

    def objective(x):
        t_rms, _ = analytic_batch(x[None, :], mech, check=False)
        return float(t_rms[0]) if np.isfinite(t_rms[0]) else 1e6

    def margins(x):
        # A hair of slack so that SLSQP, which converges onto the active constraint from either side, ends inside.
        return constraint_margins(x, mech) - 1e-7

    res = minimize(objective, x0, method="SLSQP", bounds=study.region,
                   constraints=[{"type": "ineq", "fun": margins}], options={"ftol": 1e-12, "maxiter": 200})
    x = np.clip(res.x, study.region[:, 0], study.region[:, 1])
    x = _back_to_feasible(study, np.asarray(x0, float), x)
    fx, f0 = objective(x), objective(x0)
    return (x, fx) if fx < f0 else (np.asarray(x0, float), f0)


def _back_to_feasible(study: Study, inside: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``x`` if feasible, else the feasible point nearest to it on the segment from the feasible ``inside``.

    SLSQP converges onto the active constraint from either side; a design 1e-9 mm outside is still infeasible.
    """
    mech = study.mechanism
    if check_feasibility(x, mech).feasible[0]:
        return x
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if check_feasibility(inside + mid * (x - inside), mech).feasible[0]:
            lo = mid
        else:
            hi = mid
    return inside + lo * (x - inside)


def compute_ground_truth(study: Study, step_mm: float = 0.5) -> GroundTruth:
    """Brute force over the study region on a grid of ``step_mm``, refined locally and polished.

    Parameters
    ----------
    study : Study
        The study (its region and mechanism).
    step_mm : float
        Spacing of the coarse grid (mm).

    Returns
    -------
    GroundTruth
    """
    start = time.perf_counter()
    axes = [np.arange(lo, hi + 1e-9, step_mm) for lo, hi in study.region]
    grid_x, grid_f, n_eval, n_feas = evaluate_grid(study, axes)
    if grid_x is None:
        raise ValueError(f"no feasible design on the {step_mm} mm grid of study {study.name!r}")
    # Refine on a local grid 20 times finer, then polish: the optimum usually sits on a constraint.
    fine = [np.clip(np.linspace(c - step_mm, c + step_mm, 41), lo, hi) for c, (lo, hi) in zip(grid_x, study.region,
                                                                                                  strict=True)]
    local_x, local_f, _, _ = evaluate_grid(study, [np.unique(a) for a in fine])
    if local_x is None or local_f > grid_f:
        local_x, local_f = grid_x, grid_f
    x, f = polish(study, local_x)
    report = check_feasibility(x, study.mechanism)
    return GroundTruth(
        x=[float(v) for v in x], fun=float(f), grid_x=[float(v) for v in grid_x], grid_fun=float(grid_f),
        step_mm=step_mm, n_evaluated=n_eval, n_feasible=n_feas, margins=report.margins(0),
        wall_time_s=time.perf_counter() - start, key=study_key(study, step_mm),
    )


def load_or_compute(study: Study, cache: Path, step_mm: float = 0.5) -> GroundTruth:
    """The ground truth from the JSON ``cache`` if it matches the study, else computed and cached there."""
    cache = Path(cache)
    key = study_key(study, step_mm)
    if cache.is_file():
        try:
            data = json.loads(cache.read_text())
            if data.get("key") == key:
                return GroundTruth(**data)
        except (json.JSONDecodeError, TypeError):
            pass  # a damaged cache is recomputed
    truth = compute_ground_truth(study, step_mm)
    cache.parent.mkdir(parents=True, exist_ok=True)
    cache.write_text(json.dumps(asdict(truth), indent=2))
    return truth
