"""Bayesian optimisation with a Gaussian process and expected improvement, written with numpy and scipy.

GP: constant mean (the data are standardised), anisotropic Matérn-5/2 kernel on the unit cube of the box, Gaussian
noise; hyperparameters (log length scales, log signal and noise variances) by ML-II, i.e. L-BFGS-B on the log
marginal likelihood with its analytic gradient, warm-started from the previous fit plus random restarts.
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
from scipy.linalg import cho_factor, cho_solve, solve_triangular
from scipy.optimize import OptimizeResult, minimize
from scipy.special import ndtr

from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["GaussianProcess", "expected_improvement", "minimize_bayesian"]

_SQRT5 = math.sqrt(5.0)


class GaussianProcess:
    """Gaussian-process regression with an anisotropic Matérn-5/2 kernel and ML-II hyperparameters.

    Parameters
    ----------
    length_bounds : (float, float), default (1e-2, 1e2)
        Bounds of the length scales, in the units of the inputs (the unit cube in this package).
    signal_bounds : (float, float), default (1e-2, 1e2)
        Bounds of the signal variance of the standardised outputs.
    noise_bounds : (float, float), default (1e-8, 1e-1)
        Bounds of the noise variance of the standardised outputs (a deterministic simulator drives it down).

    Attributes
    ----------
    theta : ndarray
        ``[log l_1..l_d, log signal variance, log noise variance]`` after :meth:`fit`.
    """

    def __init__(
        self,
        length_bounds: tuple[float, float] = (1e-2, 1e2),
        signal_bounds: tuple[float, float] = (1e-2, 1e2),
        noise_bounds: tuple[float, float] = (1e-8, 1e-1),
    ) -> None:
        self.length_bounds = length_bounds
        self.signal_bounds = signal_bounds
        self.noise_bounds = noise_bounds
        self.theta: np.ndarray | None = None

    def _log_bounds(self, d: int) -> list[tuple[float, float]]:
        lb = [tuple(np.log(self.length_bounds))] * d
        return lb + [tuple(np.log(self.signal_bounds)), tuple(np.log(self.noise_bounds))]

    @staticmethod
    def _scaled_sq(X1: np.ndarray, X2: np.ndarray, lengths: np.ndarray) -> np.ndarray:
        """Per-dimension squared scaled differences, shape (n1, n2, d)."""
        return ((X1[:, None, :] - X2[None, :, :]) / lengths) ** 2

    @staticmethod
    def _matern(sq: np.ndarray, signal: float) -> tuple[np.ndarray, np.ndarray]:
        """Kernel matrix and the common factor of its length-scale derivatives."""
        r = np.sqrt(np.sum(sq, axis=-1))
        e = np.exp(-_SQRT5 * r)
        k = signal * (1.0 + _SQRT5 * r + 5.0 / 3.0 * r**2) * e
        # d k / d log l_i = signal * 5/3 * (1 + sqrt5 r) exp(-sqrt5 r) * sq_i
        return k, signal * 5.0 / 3.0 * (1.0 + _SQRT5 * r) * e

    def neg_log_marginal_likelihood(self, theta: np.ndarray) -> tuple[float, np.ndarray]:
        """Negative log marginal likelihood of the standardised training data and its gradient.

        Parameters
        ----------
        theta : ndarray, shape (d + 2,)
            ``[log l_1..l_d, log signal variance, log noise variance]``.

        Returns
        -------
        value : float
        gradient : ndarray, shape (d + 2,)
        """
        X, y = self._X, self._y
        n, d = X.shape
        lengths, signal, noise = np.exp(theta[:d]), math.exp(theta[d]), math.exp(theta[d + 1])
        sq = self._scaled_sq(X, X, lengths)
        k, common = self._matern(sq, signal)
        K = k + (noise + 1e-10) * np.eye(n)
        try:
            c, low = cho_factor(K, lower=True)
        except np.linalg.LinAlgError:
            return 1e25, np.zeros(d + 2)
        alpha = cho_solve((c, low), y)
        value = 0.5 * y @ alpha + np.sum(np.log(np.diag(c))) + 0.5 * n * math.log(2.0 * math.pi)
        # d(-log L)/dθ = -0.5 tr((α αᵀ - K⁻¹) dK/dθ)
        inner = np.outer(alpha, alpha) - cho_solve((c, low), np.eye(n))
        grad = np.empty(d + 2)
        for i in range(d):
            grad[i] = -0.5 * np.sum(inner * (common * sq[:, :, i]))
        grad[d] = -0.5 * np.sum(inner * k)
        grad[d + 1] = -0.5 * noise * np.trace(inner)
        return float(value), grad

    def fit(
        self, X: np.ndarray, y: np.ndarray, *, rng: np.random.Generator | None = None, n_restarts: int = 2
    ) -> GaussianProcess:
        """Standardise the data and fit the hyperparameters by ML-II.

        Parameters
        ----------
        X : ndarray, shape (n, d)
            Inputs (the unit cube of the box in this package).
        y : ndarray, shape (n,)
            Finite outputs.
        rng : numpy.random.Generator, optional
            Source of the random restarts (none without it).
        n_restarts : int, default 2
            Random restarts besides the warm start (the previous ``theta``, or a default guess on the first fit).

        Returns
        -------
        GaussianProcess
            ``self``, fitted.
        """
        X = np.atleast_2d(np.asarray(X, dtype=float))
        y = np.asarray(y, dtype=float).ravel()
        self._mean = float(np.mean(y))
        self._scale = float(np.std(y)) or 1.0
        self._X, self._y = X, (y - self._mean) / self._scale
        d = X.shape[1]
        bounds = self._log_bounds(d)
        # Warm start from the previous fit (hyperparameters move little when one point is added), else a guess.
        if self.theta is not None and self.theta.size == d + 2:
            starts = [self.theta]
        else:
            starts = [np.concatenate([np.full(d, math.log(0.3)), [0.0, math.log(1e-4)]])]
        if rng is not None:
            lo, hi = np.array(bounds).T
            starts += [lo + rng.random(d + 2) * (hi - lo) for _ in range(n_restarts)]
        best_theta, best_value = starts[0], math.inf
        for t0 in starts:
            res = minimize(self.neg_log_marginal_likelihood, np.clip(t0, *np.array(bounds).T), jac=True,
                           method="L-BFGS-B", bounds=bounds, options={"maxiter": 200})
            if res.fun < best_value:
                best_theta, best_value = res.x, float(res.fun)
        self.theta = np.asarray(best_theta, dtype=float)
        self._factorise()
        return self

    def _factorise(self) -> None:
        X, d = self._X, self._X.shape[1]
        lengths, signal, noise = np.exp(self.theta[:d]), math.exp(self.theta[d]), math.exp(self.theta[d + 1])
        k, _ = self._matern(self._scaled_sq(X, X, lengths), signal)
        K = k + (noise + 1e-10) * np.eye(X.shape[0])
        jitter = 0.0
        while True:
            try:
                self._chol = np.linalg.cholesky(K + jitter * np.eye(K.shape[0]))
                break
            except np.linalg.LinAlgError:
                jitter = max(10.0 * jitter, 1e-10)
        self._alpha = cho_solve((self._chol, True), self._y)

    def predict(self, Xs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean and standard deviation of the latent function, in the units of ``y``.

        Parameters
        ----------
        Xs : ndarray, shape (m, d)

        Returns
        -------
        mean, std : ndarray, shape (m,)
        """
        Xs = np.atleast_2d(np.asarray(Xs, dtype=float))
        d = self._X.shape[1]
        lengths, signal = np.exp(self.theta[:d]), math.exp(self.theta[d])
        ks, _ = self._matern(self._scaled_sq(Xs, self._X, lengths), signal)
        mean = ks @ self._alpha
        v = solve_triangular(self._chol, ks.T, lower=True)
        var = np.maximum(signal - np.sum(v**2, axis=0), 1e-12)
        return self._mean + self._scale * mean, self._scale * np.sqrt(var)


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
    gp = GaussianProcess()
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
            gp.fit(Uarr, y, rng=rng, n_restarts=2 if n_it % refit_restarts_every == 0 else 0)
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
        Fitted on ``U`` and ``y``.
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
    best = float(np.min(y[finite]))
    incumbent = U[int(np.argmin(np.where(finite, y, np.inf)))]
    cand = np.vstack([rng.random((n_candidates, d)),
                      np.clip(incumbent + 0.05 * rng.standard_normal((n_local_candidates, d)), 0.0, 1.0)])
    cand = cand[problem.feasible_many(problem.from_unit(cand))]
    if cand.shape[0] == 0:
        raise BudgetExhausted("no feasible candidate found for the acquisition")
    ei = expected_improvement(*gp.predict(cand), best)
    top = np.argsort(-ei, kind="stable")[:n_polish]
    pick, pick_ei = cand[top[0]], ei[top[0]]

    def neg_ei(u: np.ndarray) -> float:
        return -float(expected_improvement(*gp.predict(u[None, :]), best)[0])

    for j in top:
        res = minimize(neg_ei, cand[j], method="L-BFGS-B", bounds=[(0.0, 1.0)] * d)
        if -res.fun > pick_ei and problem.feasible(problem.from_unit(res.x)):
            pick, pick_ei = res.x, -res.fun
    if np.min(np.linalg.norm(U - pick, axis=1)) < 1e-9:
        # EI has collapsed onto a known design: explore instead of re-simulating (cached) forever.
        pick = cand[rng.integers(cand.shape[0])]
    return pick
