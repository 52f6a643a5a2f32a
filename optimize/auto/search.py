"""The default method of :func:`mechopt.minimize`: Gaussian-process steps on a plan chosen by the budget and the
problem's declaration (:mod:`mechopt.optimize.auto.plan`), failed simulations learned as a hidden constraint.

Every phase proposes ``batch`` designs at once (the kriging believer), so that parallel workers can simulate a
step together; the budget is spent exactly, on distinct designs only.  The answer is the design of lowest simulated
value, or, on a simulator the model finds noisy, of lowest model mean (:mod:`mechopt.optimize.auto.answer`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.stats import qmc

from mechopt.optimize.auto.acquisition import propose_batch, thompson_batch
from mechopt.optimize.auto.answer import lowest_mean
from mechopt.optimize.auto.design_grid import ENUMERATE_MAX, DesignGrid, unique_rows
from mechopt.optimize.auto.gp import GaussianProcess
from mechopt.optimize.auto.least_squares_plan import least_squares_plan
from mechopt.optimize.auto.plan import GLOBAL_MAX_POINTS, Plan, choose_plan
from mechopt.optimize.auto.polish import nearest_feasible, polish_on_constraints
from mechopt.optimize.auto.quadratic_steps import QuadraticSteps
from mechopt.optimize.auto.run_state import BatchEvaluator, Predicate, ResidualBatchEvaluator
from mechopt.optimize.auto.run_state import SearchRun as _Run
from mechopt.optimize.auto.trust_region import TrustRegion

__all__ = ["AutoResult", "auto_search"]

#: Designs nearest the trust region's centre that its local GP is fitted to (bounds the cubic cost of a fit).
LOCAL_POINTS = 150
#: Designs nearest the incumbent that the model choosing the answer is fitted to
#: (:mod:`~mechopt.optimize.auto.answer`): as many as the global plan's largest fit, a fraction of a second once.
ANSWER_POINTS = 300
#: Edge of the polish box of the global plan, before the length-scale stretch (unit cube).
POLISH_LENGTH = 0.2
#: Exploration weight of the polish's lower confidence bound (in standard deviations of the model).
POLISH_KAPPA = 1.0


@dataclass
class AutoResult:
    """What the default method found.

    Attributes
    ----------
    x : (d,) ndarray
        Best design simulated successfully (NaN if none).
    fun : float
        Its objective.
    nfev, nfailed : int
        Simulations spent and those that failed.
    plan : Plan
        The plan followed.
    message : str
        One line: the plan and how the run ended.
    X, values : ndarray
        Every design simulated (n, d) and its value (NaN: failed).
    """

    x: np.ndarray
    fun: float
    nfev: int
    nfailed: int
    plan: Plan
    message: str
    X: np.ndarray = field(repr=False)
    values: np.ndarray = field(repr=False)


def _initial_design(run: _Run, n: int) -> np.ndarray:
    """The first ``n`` allowed points of a scrambled Sobol sequence (rejection of the declared constraints)."""
    d = run.U.shape[1]
    if n <= 0:
        return np.zeros((0, d))
    sobol = qmc.Sobol(d, seed=run.rng)
    chosen = np.zeros((0, d))
    for _ in range(20):
        C = run.snap(sobol.random(max(8, 2 ** int(np.ceil(np.log2(4 * n))))))
        chosen = np.vstack([chosen, C[run.allowed(C)]])
        if run.grid is not None:  # Sobol points that round to one allowed design are one design
            chosen = unique_rows(chosen)
        if chosen.shape[0] >= n:
            break
    return run.fill(chosen[:n], n)


def _global_plan(run: _Run, plan: Plan) -> None:
    d = run.U.shape[1]
    ones, zeros = np.ones(d), np.zeros(d)
    probed, steps = False, QuadraticSteps(d)
    while run.remaining > 0 and not _exhausted(run):
        if run.values.size >= GLOBAL_MAX_POINTS and run.remaining > plan.n_polish:
            # The global GP's fit grows as n³: a large budget goes on with local models (plan.GLOBAL_MAX_POINTS).
            run.prior, run.theta = True, None
            _trust_region_plan(run, plan)
            return
        k = min(plan.batch, run.remaining)
        gp, best = run.fit()
        centre = run.U[run.best_index()]
        lo, hi, kappa, first = zeros, ones, None, np.zeros((0, d))
        if run.remaining <= plan.n_polish:
            lo, hi = TrustRegion(d, length=POLISH_LENGTH, floor=_floor(run)).box(centre, gp.theta[:d])
            kappa = POLISH_KAPPA
            if run.margins is not None:
                x = polish_on_constraints(gp, centre, lo, hi, run.unit_margins, run.allowed, run.grid)
                first = first if x is None else x[None, :]
            if not probed and first.shape[0] < k:
                probed = True
                probes = _bound_probes(run, gp, centre, max(1, plan.n_polish // 2))
                first = np.vstack([first, probes[: k - first.shape[0]]])
        if first.shape[0] < k:
            step = steps.propose(run.U, run.values, run.allowed)
            if run.grid is not None and step.shape[0]:
                # On a grid the step's rounded design may be one already simulated: the round would then simulate
                # nothing, which ends the run as if every allowed design were taken.
                step = unique_rows(run.snap(step))
                step = step[run._fresh(step)]
            first = np.vstack([first, step])
        if first.shape[0] < k:
            U = propose_batch(gp, best, lo, hi, centre, k - first.shape[0], run.rng,
                              lambda C, taken=first: run.allowed(C) & _apart(C, taken), run.success_model(gp),
                              kappa=kappa, margins=run.unit_margins, grid=run.grid)
            first = np.vstack([first, U])
        n0 = run.values.size
        run.simulate(run.fill(first, k))
        if run.grid is not None and run.values.size == n0:
            # Every proposal rounded onto a design already simulated: spread the round over fresh allowed designs
            # instead (a space with a continuous variable is not exhausted); none left means the space is.
            run.simulate(run.fill(np.zeros((0, d)), k))
            if run.values.size == n0:
                return
        steps.learn(run.U[n0:], run.values[n0:])


def _bound_probes(run: _Run, gp: GaussianProcess, centre: np.ndarray, most: int) -> np.ndarray:
    """One design a half polish box inside each bound the incumbent sits on (at most ``most``).

    A variable the GP finds almost irrelevant (a length-scale of several box widths) looks the same everywhere
    to the model, and expected improvement, whose spread grows toward the faces, drifts onto a face and refines
    the other variables there: the incumbent ends on a bound the model cannot tell from the optimum.  An optimum
    on a bound is common in design (a link at its longest), so it is not assumed away; one simulation inside
    tests it, and the polish's model then has the difference to act on.  At a vertex of the bound and a declared
    constraint the probe slides along the constraint (the ventilator's optimum lies on the toggle margin, and 4 of
    10 runs at 20 simulations stopped where the margin meets |BC|'s lower bound); the model's best probe first.
    """
    step = 0.5 * POLISH_LENGTH
    active = _active_constraints(run, centre)
    probes = []
    for j in np.flatnonzero((centre <= 1e-9) | (centre >= 1.0 - 1e-9)):
        u = centre.copy()
        u[j] = step if centre[j] <= 1e-9 else 1.0 - step
        if active is not None and (active.size or not run.declared(u)[0]):
            # Off a vertex of the bound and a constraint, along the constraint (polish.nearest_feasible).
            u = nearest_feasible(u, j, run.unit_margins, active, centre)
        if u is not None:
            probes.append(u)
    P = run.snap(np.array(probes).reshape(-1, centre.size))
    P = P[run.allowed(P)] if P.shape[0] else P
    # The model's best guess first: off a vertex, most bounds lead uphill, and the budget allows few probes.
    return P[np.argsort(gp.predict(P)[0])][:most] if P.shape[0] > most else P


def _active_constraints(run: _Run, centre: np.ndarray) -> np.ndarray | None:
    """Indices of the declared constraints active at ``centre``: a margin within 1 % of that margin's spread over
    the designs simulated; None when the problem declares none."""
    if run.margins is None:
        return None
    M = run.unit_margins(np.vstack([run.U, centre]))
    spread = np.ptp(np.where(np.isfinite(M), M, np.nan), axis=0)
    return np.flatnonzero(M[-1] <= 0.01 * np.nan_to_num(spread))


def _floor(run: _Run) -> np.ndarray | None:
    """Least half-edge of a box on each variable (unit cube): one allowed value on each discrete one."""
    return None if run.grid is None else run.grid.step


def _exhausted(run: _Run) -> bool:
    """Whether a finite space has no allowed design left that was not simulated (the search has nothing to do)."""
    if run.grid is None or run.grid.count is None or run.grid.count > ENUMERATE_MAX:
        return False
    return not run.allowed(run.grid.enumerate()).any()


def _apart(U: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """Designs U farther than 1e-6 from every design already chosen this step."""
    if not chosen.shape[0]:
        return np.ones(U.shape[0], dtype=bool)
    return np.min(np.max(np.abs(U[:, None, :] - chosen[None, :, :]), axis=2), axis=1) > 1e-6


def _local_indices(run: _Run, centre: np.ndarray, most: int = LOCAL_POINTS) -> np.ndarray:
    dist = np.linalg.norm(run.U - centre, axis=1)
    return np.argsort(dist)[:most]


def _restart_centre(run: _Run) -> np.ndarray:
    """The design of largest expected improvement over the whole box under a GP of every design."""
    d = run.U.shape[1]
    saved, run.theta = run.theta, None
    gp, best = run.fit(_local_indices(run, run.U[run.best_index()]) if run.ok.sum() > 2 * LOCAL_POINTS else None)
    run.theta = saved
    U = propose_batch(gp, best, np.zeros(d), np.ones(d), run.U[run.best_index()], 1, run.rng, run.allowed,
                      run.success_model(gp), margins=run.unit_margins, sparse=True, grid=run.grid)
    return run.fill(U, 1)


def _trust_region_plan(run: _Run, plan: Plan) -> None:
    d = run.U.shape[1]
    tr = TrustRegion(d, batch=plan.batch, floor=_floor(run))
    members = list(range(run.values.size))  # designs of the current restart: its centre is their best
    while run.remaining > 0 and not _exhausted(run):
        k = min(plan.batch, run.remaining)
        vals = np.where(run.ok[members], run.values[members], np.inf)
        centre_i = members[int(np.argmin(vals))]
        gp, best = run.fit(_local_indices(run, run.U[centre_i]))
        lo, hi = tr.box(run.U[centre_i], gp.theta[:d])
        kappa = None
        if run.remaining <= plan.n_polish:
            # The last steps refine the best design found by any restart, on the model's mean.
            centre_i = run.best_index()
            gp, best = run.fit(_local_indices(run, run.U[centre_i]))
            lo, hi = TrustRegion(d, length=min(tr.length, POLISH_LENGTH), floor=tr.floor).box(run.U[centre_i],
                                                                                                 gp.theta[:d])
            kappa = 0.0
        if k > 1 and kappa is None:
            U = thompson_batch(gp, lo, hi, run.U[centre_i], k, run.rng, run.allowed, run.success_model(gp),
                               grid=run.grid)
        else:
            U = propose_batch(gp, best, lo, hi, run.U[centre_i], k, run.rng, run.allowed, run.success_model(gp),
                              kappa=kappa, margins=run.unit_margins, sparse=True, grid=run.grid)
        before, n0 = vals.min(), run.values.size
        run.simulate(run.fill(U, k))
        if run.grid is not None and run.values.size == n0:
            return  # no allowed design is left that was not simulated
        members += list(range(n0, run.values.size))
        new = run.values[n0:]
        new = new[np.isfinite(new)]
        # A restart whose centre failed has no value to beat (inf): any success is one.
        tr.update(bool(new.size) and (not np.isfinite(before) or new.min() < before - 1e-3 * abs(before)))
        if tr.collapsed and run.remaining > 0:
            tr.restart()
            n0 = run.values.size
            run.simulate(_restart_centre(run))
            members = list(range(n0, run.values.size))


def _answer(run: _Run, plan: Plan) -> tuple[int, str]:
    """Index of the answer among the designs simulated (:mod:`mechopt.optimize.auto.answer`) and, when it is not
    the lowest value simulated, a clause for the message saying why."""
    best = run.best_index()
    if plan.name == "least-squares" or run.ok.sum() < 3:
        return best, ""
    with _limited_threads():
        idx = _local_indices(run, run.U[best], ANSWER_POINTS)
        # A fit of its own, from several starts: the search's last fits were warm-started on fewer designs.
        run.theta = None
        gp, _ = run.fit(idx)
    i = lowest_mean(gp, run.U, idx[run.ok[idx]], best, run.prior)
    if i == best:
        return best, ""
    return i, (f"; the simulator looks noisy (the model's noise sd {gp.noise ** 0.5:.2g} of the values' sd): the "
               f"answer is the design of lowest model mean, not the lowest value simulated ({run.values[best]:.6g})")


def _limited_threads() -> contextlib.AbstractContextManager:
    """One BLAS thread: the GP's matrices are small, and threads fight with the simulations for the cores."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        return contextlib.nullcontext()
    return threadpool_limits(1)


def _start(run: _Run, plan: Plan, initial: np.ndarray | None) -> tuple[int, int]:
    """Simulate the designs of ``initial`` inside the box (on top of the budget), then the space-filling start;
    returns (Sobol designs planned, designs of ``initial`` simulated)."""
    n_init, n_x0 = plan.n_init, 0
    if initial is not None and len(initial):
        U0 = (np.atleast_2d(np.asarray(initial, dtype=float)) - run.lo) / run.width
        # Only designs inside the box: the line plan's reach beyond it, clipped onto a face, would be new designs
        # simulated on top of the budget (7 of 9 of a ventilator plan of 3 lines were).
        U0 = np.clip(U0[np.all((U0 >= -1e-9) & (U0 <= 1.0 + 1e-9), axis=1)], 0.0, 1.0)
        run.budget, n_x0 = run.budget + U0.shape[0], U0.shape[0]
        run.simulate(U0)
        n_init = max(0, n_init - int(run.ok.sum()))
    run.simulate(_initial_design(run, n_init))
    if run.ok.sum() < 2 and plan.name != "least-squares":
        # Too few successes to fit a model: more space-filling designs, a batch at a time, only until two
        # succeed (a simulator that fails in most of the box must not turn the whole budget into a Sobol design).
        more = _initial_design(run, run.remaining)
        for start in range(0, more.shape[0], plan.batch):
            if run.ok.sum() >= 2:
                break
            run.simulate(more[start: start + plan.batch])
    return n_init, n_x0


def auto_search(evaluate: BatchEvaluator, bounds: np.ndarray, budget: int, seed: int = 0,
                feasible: Predicate | None = None, batch: int = 1,
                margins: Callable[[np.ndarray], np.ndarray] | None = None,
                residuals: ResidualBatchEvaluator | None = None, fd_step: float = 1e-5,
                initial: np.ndarray | None = None, grid: DesignGrid | None = None) -> AutoResult:
    """Minimise a simulator within ``budget`` simulations on the plan of :func:`choose_plan`.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(X) -> (n,)`` at designs X (n, d) in the variables' units; NaN where a simulation failed.
    bounds : (d, 2) array_like
        Lower and upper bound of each variable.
    budget : int
        Simulations to spend (all of them, on distinct designs).
    seed : int
        Seed of every random choice.
    feasible : callable, optional
        Declared constraints: designs where it is False are never simulated.
    batch : int
        Designs proposed per step (simulated together).
    margins : callable, optional
        ``margins(X) -> (n, c)``: the declared constraints' margins (>= 0 feasible), for the final polish onto an
        active constraint.
    residuals : callable, optional
        A least-squares problem: ``residuals(X) -> (values, list of residual vectors or None)``, used instead of
        ``evaluate``; the plan is then ``least-squares``.
    fd_step : float
        Forward-difference step of the Gauss-Newton runs, as a fraction of each variable's range.
    initial : (m, d) ndarray, optional
        Designs simulated before (by another method, found again in the sample store): they join the model on top
        of ``budget`` and stand in for as many of the Sobol designs.
    grid : DesignGrid, optional
        The allowed designs when some variables are discrete (:mod:`~mechopt.optimize.auto.design_grid`): only
        those are proposed, each at most once; a least-squares problem then takes the global plan (a
        Gauss-Newton step would leave the grid).

    Returns
    -------
    AutoResult
    """
    bounds = np.asarray(bounds, dtype=float)
    d = bounds.shape[0]
    plan = choose_plan(d, int(budget), int(batch), least_squares=residuals is not None and grid is None)
    run = _Run(evaluate, bounds, int(budget), feasible, np.random.default_rng(seed), margins, residuals, grid)
    with _limited_threads():
        n_init, n_x0 = _start(run, plan, initial)
        # No design at all: none of the thousands tried satisfies the declared constraints (said in the message).
        if run.values.size:
            if plan.name == "least-squares":
                least_squares_plan(run, plan.batch, fd_step, run.unit_margins)
            else:
                _global_plan(run, plan)
    nfailed = int((~run.ok).sum())
    noisy = ""
    if run.ok.any():
        i, noisy = _answer(run, plan)
        x, fun = run.to_x(run.U[i]), float(run.values[i])
    else:
        x, fun = np.full(d, np.nan), float("nan")
    # With x0, its designs stand in for as many Sobol designs (and the budget is the method's share).
    said = plan if not n_x0 else replace(plan, n_init=n_init)
    message = (f"{said.describe(d, int(budget))}" + (f", after the {n_x0} designs of x0" if n_x0 else "")
               + f"; {run.values.size} simulations, {nfailed} failed"
               + ("" if run.values.size else "; no design tried satisfies the declared constraints") + noisy)
    return AutoResult(x, fun, int(run.values.size), nfailed, plan, message, run.to_x(run.U), run.values)
