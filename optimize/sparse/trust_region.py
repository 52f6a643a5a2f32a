"""Refinement by the model itself: trust-region steps on the line model corrected by every simulation so far.

The global model of a small budget (3-4 lines) is right about the shape of the landscape and wrong by a few per cent
in its level and in the position of its minimum.  A local search with forward differences on the simulator ignores
it and pays d + 1 simulations per gradient.  Here each simulation is one step: the line model plus a radial-basis
correction that interpolates its residuals at every simulated design (line samples, candidate, earlier steps) is
minimised inside a trust region around the best design, its minimiser simulated, and the region grown or shrunk by
how much of the predicted decrease came true (the classical ratio test of surrogate-based trust-region methods).
The model's gradient thus steers every step; the simulations keep it honest.  When the region has shrunk to nothing
the corrected model has nothing left to say and the caller hands what is left of the budget to the finite-difference
search, which then starts next to the optimum.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import RBFInterpolator
from scipy.optimize import minimize
from scipy.stats import qmc

__all__ = ["TrustRegionResult", "trust_region_steps"]

#: First half-width of the region, as a fraction of each variable's range.
RADIUS_START = 0.5
#: Below this half-width (fraction of the range) a step moves less than a finite-difference search would resolve.
RADIUS_MIN = 2e-3
#: Accepted steps shorter than this (fraction of the range) creep along a valley the corrected model cannot see
#: across; after two in a row the steps run down the valley along the last step, and end when that fails.
CREEP = 0.02
#: Ratio of actual to predicted decrease above which the region grows, below which it shrinks.
GROW, SHRINK = 0.75, 0.25


@dataclass
class TrustRegionResult:
    """Where the steps ended.

    Attributes
    ----------
    x : (d,) ndarray
        Best simulated design.
    value : float
        Its fitted quantity (the objective, or its square).
    n_steps : int
        Simulations taken.
    radius : float
        Final half-width (fraction of the range).
    """

    x: np.ndarray
    value: float
    n_steps: int
    radius: float


def trust_region_steps(model: Callable[[np.ndarray], np.ndarray], simulate: Callable[[np.ndarray], float],
                       feasible: Callable[[np.ndarray], np.ndarray], box: np.ndarray, X: np.ndarray, q: np.ndarray,
                       budget: int, seed: int = 0,
                       margins: Callable[[np.ndarray], np.ndarray] | None = None, batch: int = 1,
                       simulate_batch: Callable[[np.ndarray], np.ndarray] | None = None) -> TrustRegionResult:
    """Minimise a simulated quantity by steps on the corrected model, within ``budget`` simulations.

    Parameters
    ----------
    model : callable
        The line model of the fitted quantity at designs (n, d) -> (n,) (design units in, fitted units out).
    simulate : callable
        The fitted quantity of one design (d,), simulated (NaN when the simulation fails).
    feasible : callable
        Cheap feasibility of designs (n, d) -> (n,) bool.
    box : (d, 2) ndarray
        Bounds of every variable (design units).
    X, q : (n, d) and (n,) ndarrays
        Every design simulated so far and its fitted quantity (non-finite ones are ignored).
    budget : int
        Most simulations.
    seed : int
        Seed of the candidate points inside each region.
    margins : callable, optional
        Constraint margins of one design (d,) -> (m,), >= 0 when feasible, for the polish of each step.
    batch : int
        Steps proposed at once (the free workers; :meth:`_Steps.batch_step`); 1 (default): one at a time.
    simulate_batch : callable, optional
        The fitted quantity of designs (k, d) -> (k,), simulated together (default: ``simulate`` on each).

    Returns
    -------
    TrustRegionResult
    """
    box = np.asarray(box, dtype=float)
    lower, span = box[:, 0], box[:, 1] - box[:, 0]
    keep = np.isfinite(q)
    X = np.asarray(X, dtype=float)[keep]
    q = np.asarray(q, dtype=float)[keep]
    # Samples outside the region (lines run past it) inform the correction; only a feasible one may be the start.
    inside = np.asarray(feasible(X), dtype=bool)
    if not inside.any():
        return TrustRegionResult(x=np.full(lower.size, np.nan), value=float("nan"), n_steps=0, radius=0.0)
    best = int(np.flatnonzero(inside)[np.argmin(q[inside])])
    steps = _Steps(model, simulate, feasible, lower, span, (X - lower) / span, q, best, seed, margins)
    steps.simulate_batch = simulate_batch or (lambda Xb: np.array([simulate(x) for x in Xb], dtype=float))
    while steps.n_steps < budget and steps.radius >= RADIUS_MIN:
        k = min(int(batch), budget - steps.n_steps)
        if not (steps.step(budget) if k <= 1 else steps.batch_step(budget, k)):
            break
    return TrustRegionResult(x=lower + steps.u_best * span, value=steps.q_best, n_steps=steps.n_steps,
                             radius=steps.radius)


class _Steps:
    """The state of the steps, in the unit cube of the box: every simulated design, the best one and the region.

    Parameters
    ----------
    model, simulate, feasible, margins :
        As in :func:`trust_region_steps`.
    lower, span : (d,) ndarrays
        Lower bounds and widths of the box (design units).
    U, q : (n, d) and (n,) ndarrays
        The designs simulated so far (unit cube) and their finite fitted quantities.
    best : int
        Row of the feasible design to start from.
    seed : int
        Seed of the candidate points inside each region.
    """

    def __init__(self, model: Callable[[np.ndarray], np.ndarray], simulate: Callable[[np.ndarray], float],
                 feasible: Callable[[np.ndarray], np.ndarray], lower: np.ndarray, span: np.ndarray, U: np.ndarray,
                 q: np.ndarray, best: int, seed: int, margins: Callable[[np.ndarray], np.ndarray] | None) -> None:
        self.model, self.simulate, self.feasible, self.margins = model, simulate, feasible, margins
        self.lower, self.span = lower, span
        self.U, self.q = U, q
        self.u_best, self.q_best = U[best].copy(), float(q[best])
        self.radius, self.n_steps, self.creeping = RADIUS_START, 0, 0
        self.sobol = qmc.Sobol(lower.size, seed=np.random.default_rng(seed))
        self.scale = max(float(np.ptp(q)), abs(self.q_best), 1e-300)

    def base(self, Uc: np.ndarray) -> np.ndarray:
        """The line model at unit-cube designs (fitted units)."""
        return np.asarray(self.model(self.lower + np.atleast_2d(Uc) * self.span), dtype=float)

    def corrected_model(self) -> Callable[[np.ndarray], np.ndarray]:
        """The line model plus the interpolant of its residuals at every simulation so far, divided by the scale."""
        correction = residual_model(self.U, (self.q - self.base(self.U)) / self.scale)

        def corrected(Uc: np.ndarray) -> np.ndarray:
            Uc = np.atleast_2d(Uc)
            return self.base(Uc) / self.scale + correction(Uc)

        return corrected

    def proposal(self, corrected: Callable[[np.ndarray], np.ndarray], radius: float | None = None,
                 starts: int = 3) -> np.ndarray:
        """The best feasible local minimum of the corrected model in the region (half-width ``radius``, default
        the current one) around the best design, polished from its ``starts`` best cloud points."""
        radius = self.radius if radius is None else radius
        lo, hi = np.maximum(self.u_best - radius, 0.0), np.minimum(self.u_best + radius, 1.0)
        cloud = lo + self.sobol.random(512) * (hi - lo)
        cloud = np.vstack([self.u_best, cloud[np.asarray(self.feasible(self.lower + cloud * self.span), dtype=bool)]])
        values = corrected(cloud)
        return _polish(corrected, cloud[np.argsort(values)[:starts]], lo, hi, self.lower, self.span, self.margins,
                       self.feasible)

    def run(self, u: np.ndarray) -> float:
        """Simulate the unit-cube design u (counted); a finite value joins the simulated designs."""
        value = float(self.simulate(self.lower + u * self.span))
        self.n_steps += 1
        if np.isfinite(value):
            self.U, self.q = np.vstack([self.U, u]), np.append(self.q, value)
        return value

    def step(self, budget: int) -> bool:
        """One step: propose, simulate, resize the region.  False when the steps should end."""
        corrected = self.corrected_model()
        u_new = self.proposal(corrected)
        predicted = float(corrected(u_new)[0])
        here = float(corrected(self.u_best)[0])
        if np.max(np.abs(u_new - self.u_best) / np.maximum(self.radius, 1e-12)) < 1e-3 or here - predicted <= 1e-12:
            # The corrected model sees no decrease in this region: look closer.
            self.radius *= 0.5
            return True
        if np.min(np.max(np.abs(self.U - u_new), axis=1)) < 1e-7:
            self.radius *= 0.5
            return True
        value = self.run(u_new)
        if not np.isfinite(value):
            self.radius *= 0.5
            return True
        ratio = (self.q_best - value) / max((here - predicted) * self.scale, 1e-300)
        on_edge = np.any(np.abs(u_new - self.u_best) > 0.9 * self.radius)
        if value >= self.q_best:
            self.radius *= 0.5
            return True
        step = u_new - self.u_best
        self.creeping = self.creeping + 1 if np.max(np.abs(step)) < CREEP else 0
        self.u_best, self.q_best = u_new, value
        if self.creeping >= 2:
            self.creeping = 0
            return self.run_down_valley(step, budget)
        if ratio > GROW and on_edge:
            self.radius = min(2.0 * self.radius, 0.5)
        elif ratio < SHRINK:
            self.radius *= 0.5
        return True

    def run_many(self, Uc: np.ndarray) -> np.ndarray:
        """Simulate unit-cube designs (k, d) together (counted); the finite values join the simulated designs."""
        values = np.asarray(self.simulate_batch(self.lower + Uc * self.span), dtype=float).reshape(-1)
        self.n_steps += len(Uc)
        ok = np.isfinite(values)
        self.U, self.q = np.vstack([self.U, Uc[ok]]), np.append(self.q, values[ok])
        return values

    def batch_proposals(self, corrected: Callable[[np.ndarray], np.ndarray], here: float,
                        k: int) -> tuple[list[np.ndarray], list[float]]:
        """Up to ``k`` steps at once: regions of half-width r, r/2, r/4, r/8 in turn (the shrinking a failed step
        would cause, tried at the same time), each on the corrected model with the steps already chosen believed
        to return the best value so far (the constant liar, so that two steps of a round differ)."""
        ladder = max(1, min(4, int(np.floor(np.log2(self.radius / RADIUS_MIN))) + 1))
        chosen: list[np.ndarray] = []
        radii: list[float] = []
        model = corrected
        for j in range(k):
            radius = self.radius * 0.5 ** (j % ladder)
            if chosen:
                lies = np.array(chosen)
                correction = residual_model(np.vstack([self.U, lies]), np.append(
                    (self.q - self.base(self.U)) / self.scale, (self.q_best - self.base(lies)) / self.scale))

                def model(Uc: np.ndarray, correction=correction) -> np.ndarray:
                    Uc = np.atleast_2d(Uc)
                    return self.base(Uc) / self.scale + correction(Uc)

            # The lied proposals polish one start, not three: they are there to differ, and each costs the round time.
            u = self.proposal(model, radius, starts=1 if chosen else 3)
            if float(corrected(u)[0]) >= here - 1e-12 or np.max(np.abs(u - self.u_best)) < 1e-3 * radius:
                continue
            known = np.vstack([self.U, *chosen]) if chosen else self.U
            if np.min(np.max(np.abs(known - u), axis=1)) < 1e-7:
                continue
            chosen.append(u)
            radii.append(radius)
        return chosen, radii

    def batch_step(self, budget: int, k: int) -> bool:
        """One round of ``k`` steps simulated together (:meth:`batch_proposals`); the best of them is the step, the
        region takes its half-width and is resized by its ratio.  False when the steps should end."""
        corrected = self.corrected_model()
        here = float(corrected(self.u_best)[0])
        chosen, radii = self.batch_proposals(corrected, here, k)
        if not chosen:
            self.radius *= 0.5
            return True
        Uc = np.array(chosen)
        values = self.run_many(Uc)
        if not np.isfinite(values).any() or np.nanmin(values) >= self.q_best:
            self.radius = min(radii) * 0.5
            return True
        j = int(np.nanargmin(values))
        predicted = float(corrected(Uc[j])[0])
        ratio = (self.q_best - values[j]) / max((here - predicted) * self.scale, 1e-300)
        step = Uc[j] - self.u_best
        self.radius = radii[j]
        on_edge = np.any(np.abs(step) > 0.9 * self.radius)
        self.creeping = self.creeping + 1 if np.max(np.abs(step)) < CREEP else 0
        self.u_best, self.q_best = Uc[j].copy(), float(values[j])
        if self.creeping >= 2:
            self.creeping = 0
            return self.valley_batches(step, budget, k)
        if ratio > GROW and on_edge:
            self.radius = min(2.0 * self.radius, 0.5)
        elif ratio < SHRINK:
            self.radius *= 0.5
        return True

    def valley_batches(self, step: np.ndarray, budget: int, k: int) -> bool:
        """:meth:`run_down_valley` with its doubling steps simulated ``k`` at a time: the best design moves along
        them while they keep decreasing, as one at a time."""
        factor, moved = 2.0, False
        while self.n_steps < budget:
            tries, u_try = [], self.u_best
            for _ in range(min(k, budget - self.n_steps)):
                u_try = u_try + factor * step
                if (np.any(u_try < 0.0) or np.any(u_try > 1.0)
                        or not self.feasible(self.lower + u_try[None, :] * self.span)[0]):
                    break
                tries.append(u_try)
                factor *= 2.0
            if not tries:
                break
            values = self.run_many(np.array(tries))
            for u_try, value in zip(tries, values, strict=True):
                if not np.isfinite(value) or value >= self.q_best:
                    return moved
                self.u_best, self.q_best, moved = u_try, float(value), True
        return moved

    def run_down_valley(self, step: np.ndarray, budget: int) -> bool:
        """Doubling steps along ``step`` from the best design while the simulations keep decreasing.

        Creeping along a valley, the last step points down it, so a straight valley is crossed in a few
        simulations.  Returns whether the best design moved (if not, the steps have nothing left to try).
        """
        factor, moved = 2.0, False
        while self.n_steps < budget:
            u_try = self.u_best + factor * step
            if (np.any(u_try < 0.0) or np.any(u_try > 1.0)
                    or not self.feasible(self.lower + u_try[None, :] * self.span)[0]):
                break
            value = self.run(u_try)
            if not np.isfinite(value) or value >= self.q_best:
                break
            self.u_best, self.q_best, moved = u_try, value, True
            factor *= 2.0
        return moved


def residual_model(U: np.ndarray, residual: np.ndarray,
                   kernel: str = "thin_plate_spline") -> Callable[[np.ndarray], np.ndarray]:
    """Radial-basis interpolant of the residuals with a linear tail, a constant one when the designs span too few
    dimensions for a plane (few lines, all samples in one plane), nothing when even that fails.

    A tiny smoothing keeps the system solvable when two designs nearly coincide.  Fewer designs than a plane has
    coefficients (d + 1) get the constant tail at once.
    """
    for degree in (1, 0) if U.shape[0] > U.shape[1] else (0,):
        try:
            with warnings.catch_warnings():
                # scipy warns that a cubic kernel wants at least a linear tail; the constant one is the fallback
                # for designs that cannot carry a plane, and the tiny smoothing keeps it solvable.
                warnings.filterwarnings("ignore", message="`degree` should not be below", category=UserWarning)
                return RBFInterpolator(U, residual, kernel=kernel, degree=degree, smoothing=1e-10)
        except np.linalg.LinAlgError:
            continue
    return lambda Uc: np.zeros(len(np.atleast_2d(Uc)))


def _polish(corrected: Callable[[np.ndarray], np.ndarray], starts: np.ndarray, lo: np.ndarray, hi: np.ndarray,
            lower: np.ndarray, span: np.ndarray, margins: Callable[[np.ndarray], np.ndarray] | None,
            feasible: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """The best feasible local minimum of the corrected model from a few starts (all model calls, no simulation)."""
    constraints = [] if margins is None else [{"type": "ineq", "fun": lambda u: margins(lower + u * span)}]
    best_u, best_v = starts[0], float(corrected(starts[0])[0])
    for u0 in starts:
        v0 = float(corrected(u0)[0])
        if v0 < best_v:
            best_u, best_v = u0, v0
        res = minimize(lambda u: float(corrected(u)[0]), u0, method="SLSQP", bounds=list(zip(lo, hi, strict=True)),
                       constraints=constraints, options={"maxiter": 100, "ftol": 1e-12})
        u = np.clip(res.x, lo, hi)
        if np.all(np.isfinite(u)) and feasible(lower + u[None, :] * span)[0]:
            v = float(corrected(u)[0])
            if v < best_v:
                best_u, best_v = u, v
    return best_u
