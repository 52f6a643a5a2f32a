"""Bayesian optimisation with a Gaussian process and expected improvement: a plain EGO.

GP: mechopt's own (:mod:`mechopt.optimize.auto.gp`) with its extras off, i.e. ordinary kriging: a constant mean
estimated by generalised least squares, an anisotropic Matérn-5/2 kernel on the unit cube of the box, Gaussian noise,
hyperparameters (log length scales, log signal and noise variances) by ML-II (no prior, no additive component, no
quadratic trend), L-BFGS-B on the log marginal likelihood with its analytic gradient, warm-started from the previous
fit plus random restarts.  The targets are standardised before the fit.
Acquisition: expected improvement (Mockus 1978; Jones, Schonlau & Welch 1998) over the best feasible value,
maximised on random candidates (uniform plus Gaussian perturbations of the incumbent), the best few polished by
L-BFGS-B.

Constraint handling: rejection by the cheap constraints before simulation.  Candidates are filtered on
feasibility; a polished point that became infeasible falls back to its feasible seed, so only feasible designs are
simulated.  A failed simulation (NaN) enters the GP at the worst value seen so the search moves away from it.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import OptimizeResult, minimize
from scipy.special import ndtr

from mechopt.optimize.auto.gp import GaussianProcess, fit_gp
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["FIRST_GUESS", "expected_improvement", "fit_plain_gp", "minimize_bayesian"]

#: Length-scale (unit cube), signal and noise variance (standardised values) the first fit starts from.  The shared
#: GP's random starts are drawn for long length-scales; on a smooth function a plain ML-II fit from there at unit
#: signal variance can slide into the white-noise corner (every length-scale on its lower bound), which a start at
#: a third of the cube does not.
FIRST_GUESS = (0.3, 1.0, 1e-4)


def fit_plain_gp(U: np.ndarray, y: np.ndarray, rng: np.random.Generator, warm: np.ndarray | None = None,
                 restarts: int = 2) -> GaussianProcess:
    """Ordinary kriging of values at designs: the shared GP with its extras off, fitted by ML-II.

    Parameters
    ----------
    U : ndarray, shape (n, d)
        Designs in the unit cube.
    y : ndarray, shape (n,)
        Finite values, in any unit; standardised (mean 0, standard deviation 1) before the fit.
    rng : numpy.random.Generator
        Source of the random starts of the hyperparameter fit.
    warm : ndarray, optional
        A previous fit's ``theta`` (d + 2 entries), tried first; default :data:`FIRST_GUESS`'s.
    restarts : int, default 2
        Random starts besides ``warm``.

    Returns
    -------
    GaussianProcess
        Fitted on the standardised values: its :meth:`~GaussianProcess.predict` gives the mean and standard
        deviation of ``(y - mean(y)) / std(y)``.
    """
    scale = float(np.std(y)) or 1.0
    z = (np.asarray(y, dtype=float) - float(np.mean(y))) / scale
    if warm is None:
        ell, signal, noise = FIRST_GUESS
        warm = np.log(np.concatenate([np.full(U.shape[1], ell), [signal, noise]]))
    return fit_gp(U, z, rng, warm=warm, starts=restarts + 1, prior=False, additive=False, quadratic=False)


def expected_improvement(mean: np.ndarray, std: np.ndarray, best: float) -> np.ndarray:
    """Expected improvement below ``best`` of a Gaussian prediction (minimisation).

    Parameters
    ----------
    mean, std : ndarray
        Posterior mean and standard deviation.
    best : float
        Best feasible value observed.

    Returns
    -------
    ndarray
        ``(best - mean) Φ(z) + std φ(z)`` with ``z = (best - mean) / std``.
    """
    z = (best - mean) / std
    return (best - mean) * ndtr(z) + std * np.exp(-0.5 * z**2) / math.sqrt(2.0 * math.pi)


def minimize_bayesian(
    problem: CountedProblem,
    seed: int,
    *,
    n_init: int | None = None,
    n_candidates: int = 2000,
    n_local_candidates: int = 200,
    n_polish: int = 3,
    refit_restarts_every: int = 10,
) -> OptimizeResult:
    """Bayesian optimisation (GP + expected improvement) until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the initial design, candidates and hyperparameter restarts.
    n_init : int, optional
        Feasible Latin-hypercube designs simulated first, default ``max(d + 1, min(10, budget // 4))``.
    n_candidates : int, default 2000
        Uniform random candidates per acquisition.
    n_local_candidates : int, default 200
        Gaussian perturbations (sd 0.05 of the box) of the incumbent added to the candidates.
    n_polish : int, default 3
        Best candidates polished by L-BFGS-B on the expected improvement.
    refit_restarts_every : int, default 10
        Every that many iterations the hyperparameter fit adds random restarts to its warm start.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nit`` (acquisitions).
    """
    rng = np.random.default_rng(seed)
    d = problem.dim
    n0 = max(d + 1, min(10, problem.budget // 4)) if n_init is None else int(n_init)
    X0 = problem.sample_feasible(n0, rng)
    if X0.shape[0] == 0:
        return problem.result("no feasible initial design found", nit=0)
    U: list[np.ndarray] = []
    Y: list[float] = []
    theta: np.ndarray | None = None
    n_it = 0

    def observe(u: np.ndarray) -> None:
        f = problem.evaluate(problem.from_unit(u))
        U.append(u)
        Y.append(f)

    try:
        for x in X0:
            observe(problem.to_unit(x))
        while True:
            y = np.array(Y)
            finite = np.isfinite(y)
            if not finite.any():
                # Nothing to model yet (every simulation failed): keep sampling the feasible region.
                extra = problem.sample_feasible(1, rng)
                if extra.shape[0] == 0:
                    return problem.result("no further feasible design found", nit=n_it)
                observe(problem.to_unit(extra[0]))
                continue
            y = np.where(finite, y, np.max(y[finite]))
            Uarr = np.array(U)
            gp = fit_plain_gp(Uarr, y, rng, warm=theta, restarts=2 if n_it % refit_restarts_every == 0 else 0)
            theta = gp.theta
            pick = _acquire(problem, gp, Uarr, y, finite, rng, n_candidates=n_candidates,
                            n_local_candidates=n_local_candidates, n_polish=n_polish)
            observe(np.asarray(pick, dtype=float))
            n_it += 1
    except BudgetExhausted as exc:
        return problem.result(str(exc), nit=n_it)


def _acquire(
    problem: CountedProblem,
    gp: GaussianProcess,
    U: np.ndarray,
    y: np.ndarray,
    finite: np.ndarray,
    rng: np.random.Generator,
    *,
    n_candidates: int,
    n_local_candidates: int,
    n_polish: int,
) -> np.ndarray:
    """The next design to simulate: the feasible maximiser of the expected improvement, in the unit cube.

    Parameters
    ----------
    problem : CountedProblem
    gp : GaussianProcess
        Fitted on ``U`` and ``y`` standardised (:func:`fit_plain_gp`).
    U : ndarray, shape (n, d)
        Simulated designs in the unit cube.
    y : ndarray, shape (n,)
        Their values, failed simulations (``finite`` False) replaced by the worst finite one.
    finite : ndarray of bool, shape (n,)
        Which simulations gave a finite value.
    rng : numpy.random.Generator
    n_candidates, n_local_candidates, n_polish : int
        As in :func:`minimize_bayesian`.

    Returns
    -------
    ndarray, shape (d,)
        The picked feasible candidate, polished when that raised its expected improvement and kept it feasible; a
        random feasible candidate when the pick coincides with a simulated design.

    Raises
    ------
    BudgetExhausted
        If no candidate is feasible.
    """
    d = problem.dim
    # The expected improvement of the standardised values: the same maximiser, the GP's own units.
    best = float((np.min(y[finite]) - np.mean(y)) / (float(np.std(y)) or 1.0))
    incumbent = U[int(np.argmin(np.where(finite, y, np.inf)))]
    cand = np.vstack([rng.random((n_candidates, d)),
                      np.clip(incumbent + 0.05 * rng.standard_normal((n_local_candidates, d)), 0.0, 1.0)])
    cand = cand[problem.feasible(problem.from_unit(cand))]
    if cand.shape[0] == 0:
        raise BudgetExhausted("no feasible candidate found for the acquisition")
    ei = expected_improvement(*gp.predict(cand), best)
    top = np.argsort(-ei, kind="stable")[:n_polish]
    pick, pick_ei = cand[top[0]], ei[top[0]]

    def neg_ei(u: np.ndarray) -> float:
        return -float(expected_improvement(*gp.predict(u[None, :]), best)[0])

    for j in top:
        res = minimize(neg_ei, cand[j], method="L-BFGS-B", bounds=[(0.0, 1.0)] * d)
        if -res.fun > pick_ei and problem.feasible(problem.from_unit(res.x))[0]:
            pick, pick_ei = res.x, -res.fun
    if np.min(np.linalg.norm(U - pick, axis=1)) < 1e-9:
        # EI has collapsed onto a known design: explore instead of re-simulating (cached) forever.
        pick = cand[rng.integers(cand.shape[0])]
    return pick
