"""Global steps on the corrected line model: where the blend is wrong between lines, one simulation corrects it.

The blend of a few lines is right about the broad shape of a landscape and wrong between the lines, by up to the
depth of a basin narrower than the spacing.  After the lines, every simulation so far (line samples, the blend's
minima) is a measurement of that error.  Each step here

1. interpolates the residuals (simulation − blend) at every simulated design with a cubic radial-basis function,
   so the corrected model passes through every simulation and keeps the blend's shape between them;
2. minimises the corrected model over candidate designs (a scrambled Sobol cloud of the feasible region and a cloud
   around the best simulated design) that lie at least ``δ`` from every simulated design;
3. simulates that minimiser.

``δ`` cycles from wide to none (a fraction of the box): a wide ``δ`` puts the step in a part of the region no
simulation has looked at, where the corrected model is still the blend's guess (exploration); ``δ = 0`` puts it at
the corrected model's own minimum (exploitation, which converges on a basin's bottom).  This distance cycle is the
one of Regis & Shoemaker's CORS-RBF (J. Global Optim. 31, 2005, "Constrained global optimization of expensive black
box functions using radial basis functions"), with the line model as the radial-basis model's trend.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.optimize import minimize
from scipy.spatial import cKDTree
from scipy.stats import qmc

from mechopt.optimize.sparse.trust_region import residual_model

__all__ = ["DISTANCE_CYCLE", "corrected_model", "explore"]

#: Smallest distance of a step from every simulated design (fraction of the box), cycled step by step.
DISTANCE_CYCLE = (0.2, 0.1, 0.05, 0.0)
#: Candidate designs per step and dimension, over the whole region and around the best design.
_CLOUD_GLOBAL, _CLOUD_LOCAL = 1000, 300
#: Candidates a step after the first of a round is chosen among (the best of the honest corrected model).
_LIAR_CANDIDATES = 512
#: Spreads (fraction of the box) of the clouds around the best design.
_LOCAL_SIGMAS = (0.02, 0.08)


def corrected_model(trend: Callable[[np.ndarray], np.ndarray] | None, Z: np.ndarray,
                    q: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """The trend plus a cubic radial-basis interpolant of its residuals at (Z, q), in the units of q.

    Parameters
    ----------
    trend : callable or None
        Trend (the line model) at unit-cube designs (n, d) -> (n,); None for a zero trend.
    Z : (n, d) ndarray
        Simulated designs (unit cube).
    q : (n,) ndarray
        Their finite values.

    Returns
    -------
    callable
        (n, d) -> (n,), equal to q at Z.

    Notes
    -----
    The cubic kernel with a linear tail (Regis & Shoemaker's choice) rather than the thin-plate spline of the
    trust-region steps: on Hartmann-3 at 60 evaluations, 9 of 10 seeds within 0.5 % of the range with it, 7 of 10
    with the thin-plate spline.
    """
    lo_q, hi_q = float(np.min(q)), float(np.max(q))
    scale = max(hi_q - lo_q, abs(hi_q), 1e-300)

    def base(U: np.ndarray) -> np.ndarray:
        if trend is None:
            return np.zeros(len(U))
        # Outside the hull of the lines the blend extrapolates sums of exponentials; bounded so, a wild
        # extrapolation cannot pull every step into a corner the lines never saw.
        t = np.asarray(trend(U), dtype=float)
        return np.clip(np.where(np.isfinite(t), t, hi_q), lo_q - 0.5 * scale, hi_q + 0.5 * scale)

    correction = residual_model(Z, (q - base(Z)) / scale, kernel="cubic")

    def model(U: np.ndarray) -> np.ndarray:
        U = np.atleast_2d(U)
        return base(U) + scale * correction(U)

    return model


def explore(simulate: Callable[[np.ndarray], float], Z: np.ndarray, q: np.ndarray,
            trend: Callable[[np.ndarray], np.ndarray] | None, feasible: Callable[[np.ndarray], np.ndarray],
            n_steps: int, seed: int = 0, cycle: tuple[float, ...] = DISTANCE_CYCLE,
            margins: Callable[[np.ndarray], np.ndarray] | None = None, patience: int | None = None,
            batch: int = 1, simulate_batch: Callable[[np.ndarray], np.ndarray] | None = None
            ) -> tuple[np.ndarray, np.ndarray]:
    """Take ``n_steps`` simulations on the corrected model (see the module docstring), in the unit cube.

    Parameters
    ----------
    simulate : callable
        Value of one unit-cube design (d,); NaN when the simulation fails.
    Z : (n, d) ndarray
        Every design simulated so far (unit cube).
    q : (n,) ndarray
        Their values; NaN for a failed simulation (not modelled, but never repeated either).
    trend : callable or None
        The line model at unit-cube designs (n, d) -> (n,).
    feasible : callable
        Feasibility of unit-cube designs (n, d) -> (n,) bool: every step is feasible.
    n_steps : int
        Simulations to take.
    seed, cycle : int, tuple of float
        Seed of the candidate clouds; distances (fraction of the box) cycled through, wide to none.
    margins : callable, optional
        Constraint margins of unit-cube designs (n, d) -> (n, m), >= 0 feasible.  With them a step at distance 0
        polishes the cloud's best by SLSQP on the corrected model (model calls only, no simulation).
    patience : int, optional
        Stop after this many steps in a row that did not improve on the best value.
    batch : int
        Steps proposed and simulated at once (:func:`_batch_round`); 1 (default): one at a time.
    simulate_batch : callable, optional
        Values of unit-cube designs (k, d) -> (k,) simulated together (default: ``simulate`` on each).

    Returns
    -------
    Z, q : (n + k, d) and (n + k,) ndarrays
        Every design, the earlier ones first, and their values.
    """
    Z = np.atleast_2d(np.asarray(Z, dtype=float))
    q = np.asarray(q, dtype=float).reshape(-1)
    if batch > 1:
        return _explore_batches(simulate_batch or (lambda Zb: np.array([simulate(z) for z in Zb], dtype=float)),
                                Z, q, trend, feasible, n_steps, seed, cycle, margins, patience, batch)
    d = Z.shape[1]
    rng = np.random.default_rng(seed)
    sobol = qmc.Sobol(d, seed=rng)
    n_global = 2 ** int(np.ceil(np.log2(_CLOUD_GLOBAL * d)))
    idle = 0
    for step in range(int(n_steps)):
        if patience is not None and idle >= patience:
            break
        ok = np.isfinite(q)
        if not ok.any():
            break
        model = corrected_model(trend, Z[ok], q[ok])
        cloud, dist = _candidate_cloud(Z, q, feasible, sobol, rng, n_global)
        if cloud.shape[0] == 0:
            continue
        delta = cycle[step % len(cycle)]
        pick = dist >= max(delta, 1e-6)
        if not pick.any():
            continue
        cloud = cloud[pick]
        values = model(cloud)
        z = cloud[int(np.argmin(values))]
        if delta == 0.0:
            z = _polish(model, z, feasible, margins, Z)
        value = float(simulate(z))
        best_before = np.min(q[ok])
        Z, q = np.vstack([Z, z]), np.append(q, value)
        idle = 0 if value < best_before else idle + 1
    return Z, q


def _explore_batches(simulate_batch: Callable[[np.ndarray], np.ndarray], Z: np.ndarray, q: np.ndarray,
                     trend: Callable[[np.ndarray], np.ndarray] | None, feasible: Callable[[np.ndarray], np.ndarray],
                     n_steps: int, seed: int, cycle: tuple[float, ...],
                     margins: Callable[[np.ndarray], np.ndarray] | None, patience: int | None,
                     batch: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`explore` in rounds of ``batch`` steps simulated together (see :func:`_batch_round`).

    Patience counts steps, as one at a time: a round that brings nothing better adds its size to the idle count.
    """
    d = Z.shape[1]
    rng = np.random.default_rng(seed)
    sobol = qmc.Sobol(d, seed=rng)
    n_global = 2 ** int(np.ceil(np.log2(_CLOUD_GLOBAL * d)))
    idle, taken = 0, 0
    while taken < int(n_steps):
        if patience is not None and idle >= patience:
            break
        ok = np.isfinite(q)
        if not ok.any():
            break
        k = min(batch, int(n_steps) - taken)
        chosen = _batch_round(Z, q, trend, feasible, margins, sobol, rng, n_global, cycle, taken, k)
        taken += k  # a step with no candidate at its distance is spent, as one at a time
        if not chosen:
            continue
        Zb = np.array(chosen)
        values = np.asarray(simulate_batch(Zb), dtype=float).reshape(-1)
        best_before = np.min(q[ok])
        Z, q = np.vstack([Z, Zb]), np.append(q, values)
        improved = np.isfinite(values).any() and np.nanmin(values) < best_before
        idle = 0 if improved else idle + len(chosen)
    return Z, q


def _batch_round(Z: np.ndarray, q: np.ndarray, trend: Callable[[np.ndarray], np.ndarray] | None,
                 feasible: Callable[[np.ndarray], np.ndarray], margins: Callable[[np.ndarray], np.ndarray] | None,
                 sobol: qmc.Sobol, rng: np.random.Generator, n_global: int, cycle: tuple[float, ...], step: int,
                 k: int) -> list[np.ndarray]:
    """Up to ``k`` steps to simulate together: the constant liar on the corrected model.

    The steps of the round take the distances ``cycle[(step + j) % len(cycle)]``, j < k, as as many single steps
    would, the smallest first, from every simulated design and every step already chosen; each chosen step is then
    believed to return the best value so far (the lie), and the corrected model is refitted with it before the
    next is chosen, so a step at distance 0 is not chosen twice in the same basin's bottom unless the model still
    points there.  Not the kriging believer: with an interpolant, believing the model's own prediction leaves the
    model unchanged, and the steps at distance 0 would pile up at one point.
    """
    d = Z.shape[1]
    ok = np.isfinite(q)
    Zf, qf = Z[ok], q[ok]
    lie = float(np.min(qf))
    cloud, dist_simulated = _candidate_cloud(Z, q, feasible, sobol, rng, n_global)
    chosen: list[np.ndarray] = []
    if cloud.shape[0] == 0:
        return chosen
    # The trend (the line model) is the same for every lie: at the cloud, computed once a round.
    t_cloud = None if trend is None else np.asarray(trend(cloud), dtype=float)
    memo: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def cached_trend(U: np.ndarray) -> np.ndarray:
        hit = memo.get(id(U))
        return hit[1] if hit is not None and hit[0] is U else trend(U)

    def at(model: Callable[[np.ndarray], np.ndarray], idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        points = cloud[idx]
        memo.clear()
        if t_cloud is not None:
            memo[id(points)] = (points, t_cloud[idx])
        return points, model(points)

    base_trend = None if trend is None else cached_trend
    honest = corrected_model(base_trend, Zf, qf)
    v0 = at(honest, np.arange(len(cloud)))[1]
    # The closest first: the step at the corrected model's own minimum is chosen on the honest model, before any lie,
    # and is the only one polished (a polish costs more model calls than the whole cloud; the lies are there to
    # differ from it).  A lie changes the model near its design only: the others are chosen among the honest
    # model's best candidates.
    for delta in sorted(cycle[(step + j) % len(cycle)] for j in range(k)):
        dist = dist_simulated if not chosen else np.minimum(dist_simulated, cKDTree(np.array(chosen)).query(cloud)[0])
        idx = np.flatnonzero(dist >= max(delta, 1e-6))
        if idx.size == 0:
            continue
        lies = np.array(chosen).reshape(-1, d)
        if chosen:
            model = corrected_model(base_trend, np.vstack([Zf, lies]), np.append(qf, np.full(len(lies), lie)))
            points, values = at(model, idx[np.argsort(v0[idx])[:_LIAR_CANDIDATES]])
        else:
            model, points, values = honest, cloud[idx], v0[idx]
        z = points[int(np.argmin(values))]
        if delta == 0.0 and not chosen:
            z = _polish(model, z, feasible, margins, Z)
        chosen.append(z)
    return chosen


def _candidate_cloud(Z: np.ndarray, q: np.ndarray, feasible: Callable[[np.ndarray], np.ndarray], sobol: qmc.Sobol,
                     rng: np.random.Generator, n_global: int) -> tuple[np.ndarray, np.ndarray]:
    """A step's candidates: Sobol points of the region and clouds around the best design, the feasible ones likely
    to succeed, with each one's distance to the nearest simulated design.

    Failed simulations are a hidden constraint.  The corrected model is fitted to the successes only and knows
    nothing of where the simulator fails: where its extrapolation is low it pointed there step after step
    (failing Hartmann-3 at 60 simulations, ``sparse-global``: 43-54 of the 60 failed in 8 seeds of 10, the lines
    having left few successes).  So a candidate whose nearest simulated design failed is left out, unless that
    would leave none: the nearest-neighbour rule needs no length-scale, which the radial-basis model does not have,
    and hands a failure's neighbourhood back as successes are found around it.
    """
    d = Z.shape[1]
    ok = np.isfinite(q)
    best = Z[ok][np.argmin(q[ok])]
    clouds = [sobol.random(n_global)]
    for sigma in _LOCAL_SIGMAS:
        clouds.append(np.clip(best + sigma * rng.standard_normal((_CLOUD_LOCAL * d, d)), 0.0, 1.0))
    cloud = np.vstack(clouds)
    cloud = cloud[np.asarray(feasible(cloud), dtype=bool)]
    dist, nearest = cKDTree(Z).query(cloud)
    keep = ok[nearest]
    if keep.any() and not keep.all():
        cloud, dist = cloud[keep], dist[keep]
    return cloud, dist


def _polish(model: Callable[[np.ndarray], np.ndarray], z0: np.ndarray, feasible: Callable[[np.ndarray], np.ndarray],
            margins: Callable[[np.ndarray], np.ndarray] | None, Z: np.ndarray) -> np.ndarray:
    """The corrected model's local minimum from z0 (SLSQP on model calls), kept only if feasible and new."""
    constraints = [] if margins is None else [{"type": "ineq", "fun": lambda u: margins(u[None, :])[0]}]
    res = minimize(lambda u: float(model(u)[0]), z0, method="SLSQP", bounds=[(0.0, 1.0)] * z0.size,
                   constraints=constraints, options={"maxiter": 50, "ftol": 1e-12})
    z = np.clip(res.x, 0.0, 1.0)
    if (not np.all(np.isfinite(z)) or not feasible(z[None, :])[0]
            or float(model(z)[0]) > float(model(z0)[0])
            or np.min(np.linalg.norm(Z - z, axis=1)) < 1e-6):
        return z0
    return z
