"""Ground truth: a problem's true optimum by dense brute force of a fast batch evaluator, then a local polish.

The paper could not know its true optimum (10 million CAD runs).  A problem that offers ``evaluate_batch`` (the
four-bar's analytic engine: ~10⁵ designs/s) can afford a dense grid over its whole region: the grid's best feasible
design is refined on a finer local grid and polished by SLSQP with the margins as constraints.  The result is
cached in a JSON file keyed by the problem's fingerprint and the grid, so comparisons do not recompute it.  Opt-in:
``mechopt truth`` or ``mechopt study --truth``.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from mechopt.errors import InputError, MechoptError
from mechopt.optimize.problem import DesignProblem
from mechopt.optimize.sparse.feasible_point import pull_into_feasible
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.runs.fingerprint import fingerprint

__all__ = ["GroundTruth", "batch_evaluator", "compute_ground_truth", "load_or_compute"]


@dataclass
class GroundTruth:
    """The true optimum of a problem over its region.

    Attributes
    ----------
    x : list of float
        Optimal design, in the variables' units.
    fun : float
        Its objective by the batch evaluator.
    grid_x, grid_fun : list of float, float
        Best point of the coarse grid and its objective.
    step : float
        Spacing of the coarse grid (the variables' unit).
    n_evaluated, n_feasible : int
        Designs on the coarse grid, and how many of them are feasible.
    wall_time_s : float
        Time to compute it (s).
    key : str
        Hash of the problem's fingerprint and the grid.
    """

    x: list[float]
    fun: float
    grid_x: list[float]
    grid_fun: float
    step: float
    n_evaluated: int
    n_feasible: int
    wall_time_s: float
    key: str


def truth_key(problem: DesignProblem, step: float) -> str:
    """Hash of everything the ground truth depends on."""
    return fingerprint({"problem": problem.fingerprint(), "bounds": problem.bounds.tolist(), "step": step})[:16]


def batch_evaluator(problem: DesignProblem) -> Callable[[np.ndarray], np.ndarray]:
    """The problem's ``evaluate_batch``, or a one-line error: a grid needs a fast vectorised evaluator.

    Raises
    ------
    MechoptError
        The problem has none.
    """
    fn = getattr(problem, "evaluate_batch", None)
    if fn is None:
        raise MechoptError(f"problem {problem.name!r} has no fast batch evaluator (evaluate_batch); its ground truth "
                           "cannot be brute-forced here")
    return fn


def evaluate_grid(problem: DesignProblem, axes: list[np.ndarray], chunk: int = 400_000):
    """Best feasible design on the tensor grid ``axes``, its objective, the designs evaluated and feasible."""
    batch = batch_evaluator(problem)
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(axes))
    best_x, best_f, n_feasible = None, np.inf, 0
    for lo in range(0, mesh.shape[0], chunk):
        block = mesh[lo : lo + chunk]
        ok = problem.feasible(block)
        n_feasible += int(ok.sum())
        if not ok.any():
            continue
        values = np.asarray(batch(block[ok]), dtype=float)
        if not np.isfinite(values).any():
            continue
        i = int(np.nanargmin(values))
        if values[i] < best_f:
            best_x, best_f = block[ok][i], float(values[i])
    return best_x, best_f, mesh.shape[0], n_feasible


def polish(problem: DesignProblem, x0: np.ndarray) -> tuple[np.ndarray, float]:
    """SLSQP from ``x0`` on the batch evaluator, with the margins as constraints and the box as bounds."""
    batch = batch_evaluator(problem)

    def objective(x):
        value = float(np.asarray(batch(np.asarray(x, float)[None, :]), dtype=float)[0])
        return value if np.isfinite(value) else 1e12

    def margins(x):
        # A hair of slack so that SLSQP, which converges onto the active constraint from either side, ends inside.
        return problem.constraint_margins(np.atleast_2d(x))[0] - 1e-7

    constraints = [{"type": "ineq", "fun": margins}] if problem.constraints else []
    res = minimize(objective, x0, method="SLSQP", bounds=problem.bounds, constraints=constraints,
                   options={"ftol": 1e-12, "maxiter": 200})
    x = np.clip(res.x, problem.bounds[:, 0], problem.bounds[:, 1])
    x = pull_into_feasible(ModelSpace(problem), x, np.asarray(x0, float)[None, :])
    fx, f0 = objective(x), objective(x0)
    ok = problem.feasible(x)[0]
    return (x, fx) if ok and fx < f0 else (np.asarray(x0, float), f0)


def compute_ground_truth(problem: DesignProblem, step: float) -> GroundTruth:
    """Brute force over the problem's box on a grid of ``step`` (the variables' unit), refined locally, polished."""
    if not np.isfinite(step) or step <= 0:
        raise InputError(f"ground-truth grid step {step!r}: expected a number > 0")
    box = problem.bounds
    n = np.prod(np.floor((box[:, 1] - box[:, 0]) / step) + 1)
    if n > 5e8:
        raise InputError(f"ground-truth grid step {step:g} gives {n:.3g} designs; expected at most 5e8 (a larger step)")
    start = time.perf_counter()
    axes = [np.arange(lo, hi + 1e-9, step) for lo, hi in box]
    grid_x, grid_f, n_eval, n_feas = evaluate_grid(problem, axes)
    if grid_x is None:
        raise MechoptError(f"no feasible design on the {step:g} grid of problem {problem.name!r}")
    # Refine on a local grid 20 times finer, then polish: the optimum usually sits on a constraint.
    fine = [np.unique(np.clip(np.linspace(c - step, c + step, 41), lo, hi)) for c, (lo, hi) in zip(grid_x, box,
                                                                                                      strict=True)]
    local_x, local_f, _, _ = evaluate_grid(problem, fine)
    if local_x is None or local_f > grid_f:
        local_x, local_f = grid_x, grid_f
    x, f = polish(problem, local_x)
    return GroundTruth(x=[float(v) for v in x], fun=float(f), grid_x=[float(v) for v in grid_x],
                       grid_fun=float(grid_f), step=float(step), n_evaluated=int(n_eval), n_feasible=int(n_feas),
                       wall_time_s=time.perf_counter() - start, key=truth_key(problem, step))


def load_or_compute(problem: DesignProblem, cache: Path, step: float, compute: bool = True) -> GroundTruth | None:
    """The ground truth from the JSON ``cache`` if it matches, else computed and cached (or None if not ``compute``)."""
    cache = Path(cache)
    key = truth_key(problem, step)
    if cache.is_file():
        try:
            data = json.loads(cache.read_text())
            if data.get("key") == key:
                return GroundTruth(**data)
        except (OSError, json.JSONDecodeError, TypeError):
            pass  # a damaged cache is recomputed
    if not compute:
        return None
    truth = compute_ground_truth(problem, step)
    try:
        cache.parent.mkdir(parents=True, exist_ok=True)
        cache.write_text(json.dumps(asdict(truth), indent=2))
    except OSError as exc:
        raise InputError(f"cannot write the ground truth cache {cache}: {exc.strerror or exc}") from None
    return truth
