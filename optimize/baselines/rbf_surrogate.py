"""RBF / Kriging surrogate baseline: fit given samples, search the surrogate densely, simulate its optimum once.

The classic surrogate-based alternative to the project's sparse interpolation, fed with the very same samples:
``scipy.interpolate.RBFInterpolator`` (thin-plate spline by default) or the package's Matérn-5/2 Gaussian process
(Kriging, :class:`optimize.baselines.bayesian.GaussianProcess`), both on the unit cube of the box.  The surrogate is
minimised over a dense scrambled Sobol' set inside the box, kept to the cheap feasible region and, on request, to
the convex hull of the samples (where the surrogate interpolates instead of extrapolating), then polished by
Nelder-Mead on the surrogate under the same restrictions.

Constraint handling: rejection by the cheap constraints during the (free) surrogate search; the one simulated
design is feasible.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.interpolate import RBFInterpolator
from scipy.optimize import OptimizeResult, minimize
from scipy.spatial import Delaunay, QhullError
from scipy.stats import qmc

from mechopt.optimize.baselines.bayesian import GaussianProcess
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["fit_and_search_rbf"]


def fit_and_search_rbf(
    X: np.ndarray,
    y: np.ndarray,
    problem: CountedProblem,
    *,
    n_search: int = 2**17,
    surrogate: str = "rbf",
    kernel: str = "thin_plate_spline",
    smoothing: float = 0.0,
    epsilon: float | None = None,
    degree: int | None = None,
    within_hull: bool = False,
    polish: bool = True,
    evaluate: bool = True,
    seed: int = 0,
) -> OptimizeResult:
    """Fit a surrogate on given samples, minimise it over bounds ∩ feasible region, simulate the result once.

    Parameters
    ----------
    X : ndarray, shape (n, d)
        Sampled designs (those of the project's own surrogate); rows with non-finite ``y`` are dropped.
    y : ndarray, shape (n,)
        Their simulated objective values.
    problem : CountedProblem
        Bounds, cheap constraints and the counted objective (one call if ``evaluate``).
    n_search : int, default 2**17
        Sobol' points of the dense search (rounded up to a power of two).
    surrogate : {"rbf", "kriging"}
        ``RBFInterpolator`` or the ML-II Matérn-5/2 Gaussian process (posterior mean).
    kernel, smoothing, epsilon, degree
        Passed to ``scipy.interpolate.RBFInterpolator`` (``surrogate="rbf"`` only).
    within_hull : bool, default False
        Search only inside the convex hull of the samples (where the project's own surrogate claims its optimum and
        an interpolant does not extrapolate); ignored when the samples span no volume.
    polish : bool, default True
        Refine the best search point by Nelder-Mead on the surrogate.
    evaluate : bool, default True
        Simulate the surrogate optimum once (counted by ``problem``).
    seed : int, default 0
        Seed of the Sobol' scrambling and of the Kriging restarts.

    Returns
    -------
    scipy.optimize.OptimizeResult
        ``x`` surrogate optimum (feasible), ``fun`` its simulated value (the prediction when ``evaluate`` is False),
        ``predicted`` the surrogate value there, ``nfev`` simulations made here (0 or 1), ``success`` (a feasible
        optimum was found and, if simulated, gave a finite value), ``message``, ``n_candidates`` (feasible search
        points), ``hull`` (whether the hull restriction was applied).
    """
    if surrogate not in ("rbf", "kriging"):
        raise ValueError(f"surrogate must be 'rbf' or 'kriging', got {surrogate!r}")
    U, y = _finite_samples(X, y, problem)
    rng = np.random.default_rng(seed)
    predict = _fit_surrogate(U, y, surrogate, rng, kernel=kernel, smoothing=smoothing, epsilon=epsilon, degree=degree)
    hull = _hull(U) if within_hull else None
    admissible = _admissible_test(problem, hull)
    m = int(2 ** math.ceil(math.log2(max(n_search, 2))))
    cand = np.vstack([qmc.Sobol(problem.dim, rng=rng).random(m), U])
    cand = cand[admissible(cand)]
    if cand.shape[0] == 0:
        return OptimizeResult(x=np.full(problem.dim, np.nan), fun=math.inf, predicted=math.inf, nfev=0,
                              success=False, message="no feasible search point", n_candidates=0,
                              hull=hull is not None)
    pred = np.concatenate([predict(cand[i:i + 8192]) for i in range(0, cand.shape[0], 8192)])
    best_u, best_pred = cand[int(np.argmin(pred))], float(np.min(pred))
    if polish:
        best_u, best_pred = _polish(predict, admissible, best_u, best_pred)

    x = problem.from_unit(best_u)
    common = {"x": x, "predicted": best_pred, "n_candidates": int(cand.shape[0]), "hull": hull is not None}
    if not evaluate:
        return OptimizeResult(fun=best_pred, nfev=0, success=True, message="surrogate optimum (not simulated)",
                              **common)
    return _simulate_once(problem, common)


def _finite_samples(X: np.ndarray, y: np.ndarray, problem: CountedProblem) -> tuple[np.ndarray, np.ndarray]:
    """The samples with finite design and value, the designs in the unit cube; raises if too few are left."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    y = np.asarray(y, dtype=float).ravel()
    if X.shape[0] != y.size or X.shape[1] != problem.dim:
        raise ValueError(f"X must have shape (n, {problem.dim}) matching y, got {X.shape} and {y.shape}")
    keep = np.isfinite(y) & np.all(np.isfinite(X), axis=1)
    U, y = problem.to_unit(X[keep]), y[keep]
    if y.size < problem.dim + 1:
        raise ValueError(f"need at least {problem.dim + 1} finite samples, got {y.size}")
    return U, y


def _fit_surrogate(U: np.ndarray, y: np.ndarray, surrogate: str, rng: np.random.Generator, *, kernel: str,
                   smoothing: float, epsilon: float | None, degree: int | None) -> Callable[[np.ndarray], np.ndarray]:
    """The fitted surrogate's prediction on points of the unit cube, shape (m, d) to (m,)."""
    if surrogate == "rbf":
        model = RBFInterpolator(U, y, kernel=kernel, smoothing=smoothing, epsilon=epsilon, degree=degree)

        def predict(V: np.ndarray) -> np.ndarray:
            return model(V)
    else:
        gp = GaussianProcess().fit(U, y, rng=rng, n_restarts=4)

        def predict(V: np.ndarray) -> np.ndarray:
            return gp.predict(V)[0]

    return predict


def _hull(U: np.ndarray) -> Delaunay | None:
    """Delaunay triangulation of the samples' convex hull, None when they span no volume."""
    try:
        return Delaunay(U)
    except QhullError:
        return None  # coplanar samples: a hull of zero volume would exclude everything


def _admissible_test(problem: CountedProblem, hull: Delaunay | None) -> Callable[[np.ndarray], np.ndarray]:
    """Which points of the unit cube, shape (m, d), pass the cheap constraints (and lie in ``hull`` when given)."""

    def admissible(V: np.ndarray) -> np.ndarray:
        ok = problem.feasible_many(problem.from_unit(V))
        if hull is not None:
            ok &= hull.find_simplex(V) >= 0
        return ok

    return admissible


def _polish(predict: Callable[[np.ndarray], np.ndarray], admissible: Callable[[np.ndarray], np.ndarray],
            best_u: np.ndarray, best_pred: float) -> tuple[np.ndarray, float]:
    """Nelder-Mead on the surrogate from the best search point, inadmissible points valued +inf.

    Returns the polished point and its prediction if they beat ``best_pred`` and stay admissible, else the inputs.
    """
    def on_surrogate(u: np.ndarray) -> float:
        return float(predict(u[None, :])[0]) if admissible(u[None, :])[0] else math.inf

    res = minimize(on_surrogate, best_u, method="Nelder-Mead",
                   options={"xatol": 1e-9, "fatol": 1e-12, "maxfev": 2000,
                            "initial_simplex": np.vstack([best_u, best_u + 1e-3 * np.eye(best_u.size)])})
    if res.fun < best_pred and admissible(res.x[None, :])[0]:
        return res.x, float(res.fun)
    return best_u, best_pred


def _simulate_once(problem: CountedProblem, common: dict[str, Any]) -> OptimizeResult:
    """Simulate the surrogate optimum ``common["x"]`` once; the result with ``common``'s fields."""
    before = problem.nfev
    try:
        f = problem.evaluate(common["x"])
    except BudgetExhausted as exc:
        return OptimizeResult(fun=math.inf, nfev=0, success=False, message=str(exc), **common)
    return OptimizeResult(fun=f, nfev=problem.nfev - before, success=math.isfinite(f),
                          message="surrogate optimum simulated once", **common)
