"""A local least-squares search on the simulator: Gauss-Newton steps in a trust region, the Jacobian by forward
differences simulated as one batch, Broyden updates between fresh Jacobians.

A least-squares problem tells more than its objective: every residual is a function of the design, and their
Jacobian gives a model of the objective that is exact to second order at a zero-residual optimum (an inverse
problem, a path through its points).  A scalar local search (Nelder-Mead, SLSQP on the objective) sees only the
sum and needs many more simulations to reach the same accuracy.  The Jacobian's d differences are independent: they
are simulated together, which is what parallel workers want; the steps are taken one at a time, so that a run is
the same on one worker or many (trying several trust radii at once would spend simulations, the budget, on wall
time, and make the answer depend on the machine).  After an accepted step the Jacobian is updated by
Broyden's rank-one formula instead of d new simulations; it is differenced afresh only when a step on the updated
one fails (Moré, Garbow & Hillstrom's MINPACK ``hybrd`` does the same for equations).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from mechopt.optimize.least_squares.step import gauss_newton_step

__all__ = ["LocalRun", "ResidualEvaluator", "gauss_newton"]

#: ``evaluate(U) -> (values (n,), residuals)``: the objective and the residual vector (None where the simulation
#: failed) at designs U (n, d) of the unit cube; fewer rows than asked once the budget is spent.
ResidualEvaluator = Callable[[np.ndarray], tuple[np.ndarray, list]]

#: Ratio of actual to predicted decrease above which the trust region grows, below which it shrinks.
GROW, SHRINK = 0.75, 0.25
#: Smallest trust-region half-edge (unit cube) before a run is declared converged.
MIN_RADIUS = 1e-9
#: Gauss-Newton step (unit cube) below which a run has converged: the arithmetic's resolution of a design.
MIN_STEP = 1e-12
#: Relative decrease of the sum of squares below which a step counts as no progress.
MIN_GAIN = 1e-9


@dataclass
class LocalRun:
    """One Gauss-Newton run.

    Attributes
    ----------
    u : (d,) ndarray
        Best design reached (unit cube).
    value : float
        Its objective.
    merit : float
        Its sum of squared residuals.
    nfev : int
        Simulations spent (designs already simulated are not counted again by the caller).
    message : str
        Why it stopped.
    visited : list of (d,) ndarray
        The accepted designs, start first (for the multistart's record of explored basins).
    """

    u: np.ndarray
    value: float
    merit: float
    nfev: int = 0
    message: str = ""
    visited: list = field(default_factory=list)


@dataclass
class _State:
    u: np.ndarray
    r: np.ndarray
    value: float
    J: np.ndarray | None = None
    #: J was differenced at u (not only updated); ``stale``: a step on the updated J failed, difference it again.
    fresh: bool = False
    stale: bool = False
    #: A step on a fresh Jacobian gained less than MIN_GAIN: nothing left to find here.
    converged: bool = False

    @property
    def merit(self) -> float:
        return float(self.r @ self.r)


def gauss_newton(evaluate: ResidualEvaluator, u0: np.ndarray, r0: np.ndarray, value0: float, budget: int,
                 step: float, batch: int = 1, allowed: Callable[[np.ndarray], np.ndarray] | None = None,
                 margins: Callable[[np.ndarray], np.ndarray] | None = None, radius: float = 0.1,
                 stall: float = 0.0) -> LocalRun:
    """Minimise the sum of squared residuals from a simulated design, within ``budget`` new simulations.

    Parameters
    ----------
    evaluate : ResidualEvaluator
        The simulator, in unit-cube coordinates.
    u0 : (d,) ndarray
        Start (unit cube), already simulated.
    r0 : (m,) ndarray
        Its residuals.
    value0 : float
        Its objective.
    budget : int
        Most designs this run may simulate.
    step : float
        Forward-difference step (unit cube): above the simulator's noise.
    batch : int
        Workers: the Jacobian's differences are one round on any number; the run does not depend on it.
    allowed : callable, optional
        ``allowed(U) -> bool (n,)``: the declared constraints; a difference that would leave them is taken on the
        other side.
    margins : callable, optional
        ``margins(U) -> (n, c)`` declared constraint margins (>= 0 feasible), linearised in each step.
    radius : float
        Initial trust-region half-edge (unit cube).
    stall : float
        Stop when the sum of squares fell by less than this fraction between two fresh Jacobians, or over d + 1
        simulations of steps since the last check (0: run to convergence).  A multistart explores with a loose value
        and polishes its best design with 0.

    Returns
    -------
    LocalRun
    """
    s = _State(np.asarray(u0, dtype=float), np.asarray(r0, dtype=float), float(value0))
    run = LocalRun(s.u.copy(), s.value, s.merit, visited=[s.u.copy()])
    # The stall test compares the sum of squares at each fresh Jacobian with the one before, and also after every
    # d + 1 simulations of steps on updated Jacobians: a run creeping along a valley by Broyden steps spends as
    # much as one differencing afresh, and must show as much progress.
    mark, steps = np.inf, 0
    while True:
        why = _stop_reason(run, s, radius, budget)
        if why:
            run.message = why
            return run
        fresh_needed = s.J is None or s.stale
        if stall > 0.0 and (fresh_needed or steps >= s.u.size + 1):
            if mark - s.merit < stall * mark:
                run.message = f"stalled: less than {stall:g} of the sum of squares gained since the last check"
                return run
            mark, steps = s.merit, 0
        if fresh_needed:
            J = _jacobian(evaluate, s, step, allowed, run, budget)
            if J is None:
                run.message = "the budget ran out, or every difference of the Jacobian failed"
                return run
            s.J, s.fresh, s.stale = J, True, False
        n0 = run.nfev
        radius = _iterate(evaluate, s, radius, batch, margins, run, budget, allowed)
        steps += run.nfev - n0


def _stop_reason(run: LocalRun, s: _State, radius: float, budget: int) -> str:
    if run.nfev >= budget:
        return "its share of the budget is spent"
    if s.merit == 0.0:
        return "zero residuals"
    if radius < MIN_RADIUS:
        return f"converged: trust region below {MIN_RADIUS:g}"
    if s.converged:
        return f"converged: a step on a fresh Jacobian gained less than {MIN_GAIN:g} of the sum of squares"
    return ""


def _jacobian(evaluate: ResidualEvaluator, s: _State, h: float, allowed: Callable | None, run: LocalRun,
              budget: int) -> np.ndarray | None:
    """Forward differences at ``s.u``, all d simulated as one batch; the backward side where the forward one leaves
    the box or the declared constraints, or failed.  A variable with neither side allowed keeps a zero column (the
    step then leaves it where it is)."""
    d = s.u.size
    sign = np.where(s.u + h <= 1.0, 1.0, -1.0)
    J = np.zeros((s.r.size, d))
    todo, tried = np.arange(d), np.zeros(d, dtype=int)
    while todo.size:
        if allowed is not None:
            bad = ~allowed(s.u + np.diag(sign * h)[todo])
            sign[todo[bad]] *= -1.0
            tried[todo[bad]] += 1
            todo = todo[tried[todo] < 2]
            if todo.size and bad.any():
                todo = todo[allowed(s.u + np.diag(sign * h)[todo])]
        if not todo.size or budget - run.nfev < todo.size:
            break
        _, R = evaluate(s.u + np.diag(sign * h)[todo])
        run.nfev += len(R)
        if len(R) < todo.size:
            return None
        failed = np.array([j for j, rj in zip(todo, R, strict=True) if rj is None or np.shape(rj) != s.r.shape],
                          dtype=int)
        for j, rj in zip(todo, R, strict=True):
            if j not in failed:
                J[:, j] = (np.asarray(rj) - s.r) / (sign[j] * h)
        sign[failed] *= -1.0
        tried[failed] += 1
        todo = failed[tried[failed] < 2]
    return J if np.any(J) else None


def _constraint_model(margins: Callable | None, u: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    if margins is None:
        return None, None
    h = 1e-7
    U = np.vstack([u, u + h * np.eye(u.size)])
    M = np.asarray(margins(U), dtype=float)
    if M.ndim != 2 or M.shape[1] == 0:
        return None, None
    g = M[0]
    G = ((M[1:] - g) / h).T
    return np.where(np.isfinite(g), g, -1.0), np.where(np.isfinite(G), G, 0.0)


def _iterate(evaluate: ResidualEvaluator, s: _State, radius: float, batch: int, margins: Callable | None,
             run: LocalRun, budget: int, allowed: Callable | None = None) -> float:
    """One trust-region step; returns the new radius."""
    g, G = _constraint_model(margins, s.u)
    radii = np.array([radius])
    steps = [_inside(gauss_newton_step(s.J, s.r, s.u, float(rad), G, g), s.u, allowed) for rad in radii]
    keep = [i for i, p in enumerate(steps) if np.max(np.abs(p)) > 0.0]
    if not keep:
        return _reject(s, radius)
    full = steps[0]
    size = float(np.max(np.abs(full)))
    if s.fresh and size < 0.99 * radius and (
            size < MIN_STEP or s.merit - float(np.sum((s.J @ full + s.r) ** 2)) <= MIN_GAIN * s.merit):
        # The model's own minimiser lies inside the trust region, and it is where we are or promises nothing:
        # converged, no trial simulation needed.
        s.converged = True
        return radius
    P = np.array([steps[i] for i in keep])
    values, R = evaluate(np.clip(s.u + P, 0.0, 1.0))
    run.nfev += len(R)
    merits = np.array([float(np.dot(ri, ri)) if ri is not None and np.shape(ri) == s.r.shape else np.inf
                       for ri in R])
    if not merits.size or not np.isfinite(merits).any():
        return _reject(s, radius)
    i = int(np.argmin(merits))
    p, r_new = P[i], np.asarray(R[i], dtype=float)
    predicted = s.merit - float(np.sum((s.J @ p + s.r) ** 2))
    ratio = (s.merit - merits[i]) / predicted if predicted > 0 else -1.0
    if merits[i] >= s.merit:
        return _reject(s, radius)
    size = float(np.max(np.abs(p)))
    # Broyden's update keeps J consistent with the step just taken, without d new simulations.
    s.J = s.J + np.outer(r_new - s.r - s.J @ p, p) / float(p @ p)
    gain = (s.merit - merits[i]) / s.merit
    s.converged = s.fresh and gain < MIN_GAIN
    s.stale = gain < MIN_GAIN  # no gain on an updated J: confirm on a fresh one before stopping
    s.u, s.r, s.value, s.fresh = s.u + p, r_new, float(values[i]), False
    if s.merit < run.merit:
        run.u, run.value, run.merit = s.u.copy(), s.value, s.merit
        run.visited.append(s.u.copy())
    if ratio > GROW and size >= 0.99 * radii[i]:
        return 2.0 * radius
    if ratio < SHRINK:
        return max(0.25 * size, 1e-3 * radius)
    return max(radii[i], size)


def _inside(p: np.ndarray, u: np.ndarray, allowed: Callable | None) -> np.ndarray:
    """The step, halved until it satisfies the declared constraints (their linearisation can overshoot a curved
    one); zero when 30 halvings do not."""
    if allowed is None:
        return p
    for _ in range(30):
        if allowed(np.clip(u + p, 0.0, 1.0)[None, :])[0]:
            return p
        p = 0.5 * p
    return np.zeros_like(p)


def _reject(s: _State, radius: float) -> float:
    """A failed step: difference the Jacobian afresh if it was only updated, else shrink the trust region."""
    if not s.fresh:
        s.stale = True
        return radius
    return 0.25 * radius
