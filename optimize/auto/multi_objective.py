"""The default method on trade-offs: several objectives (expected hypervolume improvement, or ParEGO) and limits on
simulated outputs (constrained EI).

Several objectives are handled by the expected hypervolume improvement of
:mod:`~mechopt.optimize.auto.hypervolume_proposal`: one GP per objective, the closed-form EHVI of the current
feasible front, batches of W workers by believed fronts.  A problem that declares its objectives' ``ideal`` and
``nadir`` fixes the normalisation of the improvement, and every GP of the search then takes the length-scale
prior.  ParEGO (Knowles 2006) is the alternative
(``scalarise=True``, the option ``front="parego"``), and the fallback when the front's box decomposition would grow
past :data:`~mechopt.optimize.auto.hypervolume_proposal.MOST_BOXES` (four objectives and a large front): each
proposal draws a weight vector λ uniformly from the simplex, scalarises the normalised objectives of every simulated
design by the augmented Chebyshev function s = max_j λ_j z_j + ρ Σ_j λ_j z_j (ρ = 0.05; z_j the objective mapped to
[0, 1] over the designs simulated), fits the default method's Gaussian process to s and maximises its expected
improvement; a batch of W workers takes W weights.

Limits on simulated outputs: each limited output has its own GP (:mod:`~mechopt.optimize.auto.limit_models`) and
the acquisition is log EI (or log EHVI) + log P(every limit met) (constrained EI); the incumbent is the best design
that met the limits, and until one has, the search maximises the probability of meeting them.  One objective with
limits is the ParEGO loop with λ = (1).  Failed simulations are learned as in
:func:`~mechopt.optimize.auto.search.auto_search` (:class:`~mechopt.optimize.auto.feasibility.SuccessModel`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from mechopt.optimize.auto.acquisition import propose_batch
from mechopt.optimize.auto.feasibility import SuccessModel
from mechopt.optimize.auto.gp import GaussianProcess, fit_gp
from mechopt.optimize.auto.hypervolume_proposal import affordable, propose_by_hypervolume
from mechopt.optimize.auto.limit_models import LimitModels
from mechopt.optimize.auto.output_models import OutputModels
from mechopt.optimize.auto.search import _limited_threads

__all__ = ["TradeOffRun", "initial_size", "trade_off_search"]

#: Weight of the augmented Chebyshev function's linear term (Knowles 2006): it breaks ties between weakly dominated
#: designs.
RHO = 0.05

#: ``evaluate(X) -> (F (n, k), G (n, m), ok (n,))``: minimised objectives and limited outputs of designs X (n, d) in
#: the variables' units, and whether each simulation succeeded.
TradeOffEvaluator = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclass
class TradeOffRun:
    """Every design the search simulated, in order.

    Attributes
    ----------
    X : (n, d) ndarray
        Designs, in the variables' units.
    F : (n, k) ndarray
        Minimised objectives (NaN where the simulation failed).
    G : (n, m) ndarray
        Limited outputs (NaN where failed).
    ok : (n,) bool ndarray
        Simulations that succeeded.
    """

    X: np.ndarray
    F: np.ndarray
    G: np.ndarray
    ok: np.ndarray


def initial_size(d: int, budget: int) -> int:
    """Space-filling designs before the first model: 2(d + 1), or a tenth of a large budget."""
    return int(min(budget, max(2 * (d + 1), budget // 10)))


class _State:
    """The designs so far (unit cube) and the door to the simulator."""

    def __init__(self, evaluate: TradeOffEvaluator, bounds: np.ndarray, budget: int, k: int, m: int,
                 feasible: Callable[[np.ndarray], np.ndarray] | None) -> None:
        self.evaluate, self.budget, self.feasible = evaluate, budget, feasible
        self.lo, self.width = bounds[:, 0], bounds[:, 1] - bounds[:, 0]
        d = bounds.shape[0]
        self.U, self.F, self.G = np.zeros((0, d)), np.zeros((0, k)), np.zeros((0, m))
        self.ok = np.zeros(0, dtype=bool)

    @property
    def remaining(self) -> int:
        return self.budget - self.U.shape[0]

    def to_x(self, U: np.ndarray) -> np.ndarray:
        return self.lo + np.clip(U, 0.0, 1.0) * self.width

    def allowed(self, U: np.ndarray) -> np.ndarray:
        """Designs not simulated yet that satisfy the declared constraints."""
        U = np.atleast_2d(U)
        fresh = np.ones(U.shape[0], dtype=bool)
        if self.U.shape[0]:
            fresh = np.min(np.max(np.abs(U[:, None, :] - self.U[None, :, :]), axis=2), axis=1) > 1e-6
        if self.feasible is not None and fresh.any():
            fresh[fresh] = self.feasible(self.to_x(U[fresh]))
        return fresh

    def simulate(self, U: np.ndarray) -> None:
        U = np.atleast_2d(U)[: self.remaining]
        if not U.shape[0]:
            return
        F, G, ok = self.evaluate(self.to_x(U))
        self.U = np.vstack([self.U, U])
        self.F = np.vstack([self.F, np.asarray(F, float).reshape(U.shape[0], -1)])
        self.G = np.vstack([self.G, np.asarray(G, float).reshape(U.shape[0], self.G.shape[1])])
        self.ok = np.concatenate([self.ok, np.asarray(ok, bool) & np.all(np.isfinite(F), axis=1)])


def _space_filling(state: _State, n: int, rng: np.random.Generator) -> np.ndarray:
    """The first ``n`` allowed points of a scrambled Sobol sequence."""
    d = state.U.shape[1]
    sobol = qmc.Sobol(d, seed=rng)
    chosen = np.zeros((0, d))
    for _ in range(20):
        C = sobol.random(max(8, 2 ** int(np.ceil(np.log2(4 * max(n, 1))))))
        chosen = np.vstack([chosen, C[state.allowed(C)]])
        if chosen.shape[0] >= n:
            break
    return chosen[:n]


class _Scalarised:
    """The GP of a scalarisation of the objectives, refitted for each weight vector (warm-started)."""

    def __init__(self) -> None:
        self.theta: np.ndarray | None = None
        self.fitted_n = 0

    def fit(self, U: np.ndarray, s: np.ndarray, rng: np.random.Generator) -> tuple[GaussianProcess, np.ndarray]:
        full = self.theta is None or U.shape[0] >= 1.25 * self.fitted_n
        if full:
            self.fitted_n = U.shape[0]
        # The scalarisation of [0, 1] objectives has no long tail to compress: a z-score (the Yeo-Johnson fit of
        # the global model cost 40 ms a proposal).
        y = (s - s.mean()) / (float(np.std(s)) or 1.0)
        gp = fit_gp(U, y, rng, warm=self.theta, starts=3 if full else 1, maxiter=100 if full else 30, prior=False,
                    spacing_floor=True)
        self.theta = gp.theta
        return gp, y


def chebyshev(Z: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Augmented Chebyshev scalarisation (n,) of normalised objectives Z (n, k) with weights (k,)."""
    W = Z * weights
    return W.max(axis=1) + RHO * W.sum(axis=1)


def _propose(state: _State, limits: LimitModels, model: _Scalarised, q: int, rng: np.random.Generator,
             margins: Callable[[np.ndarray], np.ndarray] | None) -> np.ndarray:
    """``q`` designs: one per random weight vector (several objectives), or a believer batch (one objective)."""
    ok = state.ok
    U, F = state.U[ok], state.F[ok]
    lo, span = F.min(axis=0), np.ptp(F, axis=0)
    Z = (F - lo) / np.where(span > 0, span, 1.0)
    met = limits.met(state.G[ok])
    if limits.m:
        limits.fit(U, state.G[ok], rng)

    def log_feasible(C: np.ndarray, success: SuccessModel | None) -> np.ndarray:
        total = limits.log_probability(C) if limits.m else np.zeros(np.atleast_2d(C).shape[0])
        return total + success.log_probability(C) if success is not None else total

    k = F.shape[1]
    rounds = [(np.ones(1), q)] if k == 1 else [(rng.dirichlet(np.ones(k)), 1) for _ in range(q)]
    chosen = np.zeros((0, U.shape[1]))
    d = U.shape[1]
    for weights, n in rounds:
        s = chebyshev(Z, weights)
        gp, y = model.fit(U, s, rng)
        # The incumbent is the best design meeting the limits; with none yet, the worst value makes the
        # improvement broad and the probability of meeting the limits chooses.
        best = float(y[met].min()) if met.any() else float(y.max())
        centre = U[int(np.argmin(np.where(met, y, np.inf)))] if met.any() else U[int(np.argmin(y))]
        taken = chosen

        def allowed(C: np.ndarray, taken: np.ndarray = taken) -> np.ndarray:
            a = state.allowed(C)
            if taken.shape[0]:
                a &= np.min(np.max(np.abs(C[:, None, :] - taken[None, :, :]), axis=2), axis=1) > 1e-6
            return a

        # Failures are learned with the scalarisation's length-scales, as the single-objective search does.
        success = None if state.ok.all() else SuccessModel(state.U, state.ok, gp.theta[:d])
        use_lf = limits.m > 0 or success is not None
        new = propose_batch(gp, best, np.zeros(d), np.ones(d), centre, n, rng, allowed,
                            (lambda C, success=success: log_feasible(C, success)) if use_lf else None,
                            margins=margins)
        chosen = np.vstack([chosen, new])
    return chosen


def _front_affordable(state: _State, limits: LimitModels) -> bool:
    """Whether the expected hypervolume improvement's boxes of the current front are few enough."""
    G = state.G[state.ok]
    return affordable(state.F[state.ok], limits.met(G))


def _propose_front(state: _State, limits: LimitModels, objectives: OutputModels, q: int, rng: np.random.Generator,
                   margins: Callable[[np.ndarray], np.ndarray] | None,
                   declared: tuple[np.ndarray, np.ndarray] | None) -> np.ndarray:
    """``q`` designs by expected hypervolume improvement (:mod:`~mechopt.optimize.auto.hypervolume_proposal`)."""
    ok = state.ok
    U, F, G = state.U[ok], state.F[ok], state.G[ok]
    met = limits.met(G)
    if limits.m:
        limits.fit(U, G, rng)
    objectives.fit(U, F, rng)
    d = U.shape[1]
    # Failures are learned with the first objective's length-scales, as the single-objective search does.
    success = None if ok.all() else SuccessModel(state.U, ok, objectives.models[0][0].theta[:d])

    def log_feasible(C: np.ndarray) -> np.ndarray:
        total = limits.log_probability(C)
        return total + success.log_probability(C) if success is not None else total

    use_lf = limits.m > 0 or success is not None
    return propose_by_hypervolume(U, F, met, objectives, q, rng, state.allowed, log_feasible if use_lf else None,
                                  margins, declared)


def trade_off_search(evaluate: TradeOffEvaluator, bounds: np.ndarray, budget: int, k: int, lower: np.ndarray,
                     upper: np.ndarray, seed: int = 0, feasible: Callable[[np.ndarray], np.ndarray] | None = None,
                     batch: int = 1, margins: Callable[[np.ndarray], np.ndarray] | None = None,
                     initial: np.ndarray | None = None, scalarise: bool = False,
                     declared: tuple[np.ndarray, np.ndarray] | None = None) -> TradeOffRun:
    """Spend ``budget`` simulations on a Pareto front (k > 1) or on the best design meeting the limits (k = 1).

    Parameters
    ----------
    evaluate : callable
        ``evaluate(X) -> (F (n, k), G (n, m), ok (n,))`` at designs X (n, d) in the variables' units.
    bounds : (d, 2) array_like
        Lower and upper bound of each variable.
    budget : int
        Simulations to spend, on distinct designs.
    k : int
        Number of objectives.
    lower, upper : (m,) array_like
        Limits of the outputs ``evaluate`` returns in G (-inf / +inf where open).
    seed : int
        Seed of every random choice.
    feasible : callable, optional
        Declared constraints: designs where it is False are never simulated.
    batch : int
        Designs proposed per step (simulated together).
    margins : callable, optional
        ``margins(X) -> (n, c)`` of the declared constraints: proposals may end on one.
    initial : (p, d) ndarray, optional
        Designs to simulate first, inside the bounds (they count in the budget).
    scalarise : bool
        Several objectives by ParEGO's random scalarisations throughout, instead of the expected hypervolume
        improvement (which the search leaves for ParEGO only when the front outgrows its box decomposition).
    declared : (ideal (k,), nadir (k,)), optional
        The objectives' scale the problem declares (minimised sense; k > 1).  The expected hypervolume improvement
        then normalises by it (:func:`~mechopt.optimize.auto.hypervolume_proposal.propose_by_hypervolume`) and
        every GP of the search takes the length-scale prior.

    Returns
    -------
    TradeOffRun
    """
    bounds = np.asarray(bounds, dtype=float)
    d = bounds.shape[0]
    rng = np.random.default_rng(seed)
    declared = declared if k > 1 else None
    # With a fixed reference a design predicted beyond it earns nothing, and the search follows the models'
    # extrapolation into the box: plain marginal likelihood left DTLZ2-3's distance variables at the length-scales'
    # floor or ceiling, a model that never finds the front; the prior keeps them resolvable (BoTorch's default).
    # With the front's own scale the prior measured worse (docs/guide/trade_offs.md).
    prior = declared is not None
    limits = LimitModels(lower, upper, prior)
    state = _State(evaluate, bounds, int(budget), k, limits.m, feasible)
    unit_margins = None if margins is None else (lambda U: margins(state.to_x(U)))
    with _limited_threads():
        if initial is not None and len(initial):
            state.simulate((np.atleast_2d(np.asarray(initial, float)) - state.lo) / state.width)
        state.simulate(_space_filling(state, max(0, initial_size(d, int(budget)) - state.U.shape[0]), rng))
        model, objectives = _Scalarised(), OutputModels(k, prior)
        while state.remaining > 0:
            q = min(max(1, int(batch)), state.remaining)
            if state.ok.sum() < 2:
                U = _space_filling(state, q, rng)
            elif k > 1 and scalarise is False and _front_affordable(state, limits):
                U = _propose_front(state, limits, objectives, q, rng, unit_margins, declared)
            else:
                U = _propose(state, limits, model, q, rng, unit_margins)
            if not U.shape[0]:
                U = _space_filling(state, q, rng)
                if not U.shape[0]:
                    break
            state.simulate(U)
    return TradeOffRun(state.to_x(state.U), state.F, state.G, state.ok)
