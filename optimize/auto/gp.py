"""A Gaussian process on the unit cube: a Matérn-5/2 kernel with one length-scale per variable plus a first-order
additive component, hyperparameters by maximum marginal likelihood (ML-II), optionally with a weak prior, several
starts.

The additive component (Duvenaud, Nickisch & Rasmussen 2011, first order) is the mean over the variables of a
one-variable Matérn-5/2 with the same length-scales, with a variance of its own; the evidence shares the prior
variance between the two components.  Where the objective is a sum of one contribution per variable (or nearly:
a sum of terms, a separable well in each variable), the model then predicts a combination of the variables no
design has from what each variable did elsewhere: a variable left in the wrong one of its wells is seen to be
wrong.  The product kernel alone cannot, and expects nothing from a move it has not sampled near.  Where the
variables interact, the evidence gives the additive component (nearly) nothing, and the model is the product's
(the measurements: ``docs/guide/design-evidence.md``).  A component the evidence gives
under 1e-3 of the product's variance is left out of the fitted model, which then costs what the product alone does.

The hyperparameters are fitted under a constant prior mean, estimated by generalised least squares (ordinary
kriging's mean, the model of DACE and of EGO: Jones, Schonlau & Welch 1998; BoTorch's constant mean fitted by
maximum likelihood is the same estimate); where the designs pay for one, the model predicts with a quadratic trend
in its place (:mod:`~mechopt.optimize.auto.trend`).  The plain average of the targets is a biased estimate of the
function's level: a minimiser piles its designs into the low basins, so the average sinks, and with it what the
model expects wherever it has not looked; every unexplored corner then seems promising.  Generalised least squares
weighs a cluster of correlated designs about as one.  The level's own uncertainty is left out of the variance, as
BoTorch does: on a smooth function with long length-scales the level is poorly determined, and that term made the
far corners of a trust region look promising (Rosenbrock-6 at 300 simulations left its valley).

The optional prior on the length-scales is the dimension-scaled log-normal of Hvarfner, Hellsten & Nardi (2024):
log ℓ ~ N(√2 + ½ log d, √3), derived for many variables, where a few dozen designs leave most length-scales
undetermined and plain ML-II collapses them onto tiny values (every unexplored point then looks equally
promising).  The trust regions' local fits use it; the global model does not, in any number of variables: there
the designs fix the length-scales and the prior only biases them long (measured up to 12 variables,
:mod:`mechopt.optimize.auto.plan`).
Targets are expected standardised (:mod:`mechopt.optimize.auto.transform`).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import cho_solve, solve_triangular
from scipy.linalg.lapack import dpotri
from scipy.optimize import minimize

from mechopt.optimize.auto.additive_kernel import additive_gradient, additive_gram, additive_matern
from mechopt.optimize.auto.trend import Trend

__all__ = ["GaussianProcess", "fit_gp", "noise_log_bayes_factor"]

_SQRT5 = math.sqrt(5.0)
#: Bounds of log length-scale (unit cube), log signal variance and log noise variance (standardised targets).
_LOG_ELL = (math.log(5e-3), math.log(50.0))
_LOG_SIGNAL = (math.log(0.05), math.log(20.0))
#: The noise floor is there for the factorisation only, as scikit-learn's ``alpha=1e-10``: a simulator is
#: deterministic, and a noisy one lifts the fitted noise above the floor by itself.  A floor of 1e-6 of the
#: standardised variance smoothed away what the designs around a minimum had resolved (Rosenbrock-6 at 300
#: simulations ended at a median 2.50 in a valley the model could no longer see down; 0.67 with this floor).
_LOG_NOISE = (math.log(1e-10), math.log(0.1))
#: Bounds of the log variance of the additive component (standardised targets), and its start.
_LOG_ADDITIVE = (math.log(1e-4), math.log(20.0))
_LOG_ADDITIVE_START = math.log(0.1)
#: Log of the share of the product's variance below which the additive component is left out of a fitted model.
_NEGLIGIBLE = math.log(1e-3)
#: L-BFGS-B's relative tolerance on the log posterior: 1e-7 of it is a few 1e-5 nats at 150 designs, far below any
#: difference of evidence that tells hyperparameters apart.  scipy's default (2.2e-9) spends about half the
#: evaluations of a warm-started refit in line searches that move the evidence by less.
_FTOL = 1e-7
#: Correlation with the nearest design below which a fitted model is taken for white noise (:func:`fit_gp`).
_NO_NEIGHBOUR = 0.05
#: Jitter added, in turn, to the diagonal of a covariance matrix whose factorisation failed (fraction of the signal).
_JITTER = (0.0, 1e-10, 1e-8, 1e-6, 1e-4)


def _matern(U: np.ndarray, V: np.ndarray, ell: np.ndarray, signal: float) -> tuple[np.ndarray, np.ndarray]:
    """Matérn-5/2 covariance of designs U (n, d) and V (m, d), and its factor W with ∂k/∂log ℓ_k = W (Δ_k/ℓ_k)²."""
    A, B = U / ell, V / ell
    r2 = np.maximum(np.sum(A * A, 1)[:, None] + np.sum(B * B, 1)[None, :] - 2.0 * A @ B.T, 0.0)
    r = np.sqrt(r2)
    e = np.exp(-_SQRT5 * r)
    K = signal * (1.0 + _SQRT5 * r + 5.0 / 3.0 * r2) * e
    W = signal * 5.0 / 3.0 * (1.0 + _SQRT5 * r) * e
    return K, W


def _additive(U: np.ndarray, V: np.ndarray, ell: np.ndarray, variance: float) -> np.ndarray:
    """First-order additive covariance of designs U (n, d) and V (m, d): ``variance`` times the mean over the
    variables of a one-variable Matérn-5/2."""
    symmetric, U = V is U, np.ascontiguousarray(U, dtype=float)
    # The designs' own covariance (a fit's, a batch's draws): each pair once, the same numbers.
    K = additive_gram(U, ell) if symmetric else additive_matern(U, np.ascontiguousarray(V, dtype=float), ell)
    return variance / U.shape[1] * K


def _covariance(U: np.ndarray, V: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Covariance of designs U and V under ``theta``: the Matérn product, plus the additive component when
    ``theta`` has its variance (d + 3 entries)."""
    d = U.shape[1]
    ell = np.exp(theta[:d])
    K, _ = _matern(U, V, ell, math.exp(theta[d]))
    if theta.size > d + 2:
        K = K + _additive(U, V, ell, math.exp(theta[d + 2]))
    return K


def _cholesky(K: np.ndarray, signal: float) -> np.ndarray:
    """Lower Cholesky factor of K, with the least jitter of ``_JITTER`` that lets it succeed.

    Near the noise floor, designs a hair apart (a batch's kriging believer, a polish that lands next to the
    incumbent) leave K singular to rounding; a little more noise on the diagonal is the least change to the model.
    """
    for jitter in _JITTER:
        try:
            return np.linalg.cholesky(K + jitter * signal * np.eye(K.shape[0]) if jitter else K)
        except np.linalg.LinAlgError:
            continue
    raise np.linalg.LinAlgError(f"covariance of {K.shape[0]} designs not positive definite even with jitter "
                                f"{_JITTER[-1]:g} of the signal variance")


class GaussianProcess:
    """A fitted GP: posterior mean and standard deviation of standardised targets at new designs.

    Parameters
    ----------
    X : (n, d) ndarray
        Designs in the unit cube.
    y : (n,) ndarray
        Standardised targets.
    theta : (d + 2,) or (d + 3,) ndarray
        log length-scales, log signal variance (the product kernel's), log noise variance and, with d + 3 entries,
        the additive component's log variance.
    quadratic : bool, optional
        The prior mean's form (:class:`~mechopt.optimize.auto.trend.Trend`); default: quadratic where the designs
        pay for it (their number and the information criterion).
    believed : int
        How many of the last designs are a batch's believed values (:meth:`believe`), taken as exact.
    """

    def __init__(self, X: np.ndarray, y: np.ndarray, theta: np.ndarray, quadratic: bool | None = None,
                 believed: int = 0) -> None:
        self.X, self.y, self.theta = np.asarray(X, float), np.asarray(y, float), np.asarray(theta, float)
        self.believed = int(believed)
        d = self.X.shape[1]
        self.signal, self.noise = math.exp(self.theta[d]), math.exp(self.theta[d + 1])
        if self.theta.size > d + 2:
            # The prior variance of f: the product's and the additive component's.
            self.signal += math.exp(self.theta[d + 2])
        #: The designs' prior covariance (no noise), kept for :func:`_sees_no_neighbour`.
        self.K = _covariance(self.X, self.X, self.theta)
        K = self.K.copy()
        # A believed design is a value of the latent function, not a noisy simulation: no noise on its diagonal.
        simulated = np.arange(self.X.shape[0] - self.believed)
        K[simulated, simulated] += self.noise
        self.L = _cholesky(K, self.signal)
        #: The prior mean (generalised least squares).
        self.trend = Trend(self.X, self.y, self.L, quadratic)
        self.alpha = cho_solve((self.L, True), self.y - self.trend(self.X), check_finite=False)

    def predict(self, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean and standard deviation (of the latent function, no noise) at designs U (m, d), the prior
        mean taken as known."""
        U = np.atleast_2d(U)
        Ks = _covariance(U, self.X, self.theta)
        mean = self.trend(U) + Ks @ self.alpha
        V = solve_triangular(self.L, Ks.T, lower=True, check_finite=False)
        var = np.maximum(self.signal - np.sum(V * V, axis=0), 1e-12 * self.signal)
        return mean, np.sqrt(var)

    def draw(self, U: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` joint draws (n, m) of the latent function at designs U (m, d) from the posterior."""
        U = np.atleast_2d(U)
        Ks = _covariance(U, self.X, self.theta)
        Kss = _covariance(U, U, self.theta)
        V = solve_triangular(self.L, Ks.T, lower=True, check_finite=False)
        C = Kss - V.T @ V
        try:
            # The jitter keeps near-duplicate candidates from making the factor fail; 1e-6 of the signal is below
            # anything the draws' argmin can resolve.
            F = np.linalg.cholesky(C + 1e-6 * self.signal * np.eye(U.shape[0]))
        except np.linalg.LinAlgError:
            w, Q = np.linalg.eigh(C)
            F = Q * np.sqrt(np.maximum(w, 0.0))
        return self.trend(U) + Ks @ self.alpha + (F @ rng.standard_normal((U.shape[0], n))).T

    def believe(self, U: np.ndarray) -> GaussianProcess:
        """The same GP with designs U (m, d) added at their posterior mean (the kriging believer of a batch).

        The believed values are of the latent function, exactly: its variance there is then zero, as it would be
        after the simulation on a deterministic simulator.  With the noise of the simulated designs on them, a fitted
        nugget left variance in place (0.25 of a standard deviation of 0.39 under a noise variance of 0.1, in the
        tests), and the next design of the batch could go next to the believed one for the same expected improvement
        of the latent function.
        """
        U = np.atleast_2d(U)
        mean, _ = self.predict(U)
        return GaussianProcess(np.vstack([self.X, U]), np.concatenate([self.y, mean]), self.theta,
                               self.trend.quadratic, self.believed + U.shape[0])


def _inverse(L: np.ndarray) -> np.ndarray:
    """K⁻¹ from the lower Cholesky factor L of K by LAPACK's ``potri`` (a triangular inverse and one product).

    ``potri`` takes a little over half as long as solving for the identity's n columns, which costs a sixth of the
    method's own time at 6-D.
    """
    inv, info = dpotri(L, lower=1)
    if info:
        raise np.linalg.LinAlgError(f"potri failed with info {info}")
    # potri fills the lower triangle only; mirrored in place (np.tril plus its transpose takes twice as long).
    inv = np.tril(inv)
    inv += inv.T
    inv[np.diag_indices_from(inv)] *= 0.5
    return inv


def _neg_log_posterior(theta: np.ndarray, X: np.ndarray, y: np.ndarray, prior_mu: float,
                       w: float) -> tuple[float, np.ndarray]:
    n, d = X.shape
    ell, signal, noise = np.exp(theta[:d]), math.exp(theta[d]), math.exp(theta[d + 1])
    K, W = _matern(X, X, ell, signal)
    Kp = K.copy()
    additive = theta.size > d + 2
    if additive:
        # The component's weight: its variance over the d terms it averages.
        weight, Xc = math.exp(theta[d + 2]) / d, np.ascontiguousarray(X)
        Ka = weight * additive_gram(Xc, ell)
        K += Ka
    K[np.diag_indices_from(K)] += noise
    try:
        L = np.linalg.cholesky(K)
        Kinv = _inverse(L)
    except np.linalg.LinAlgError:
        return 1e10, np.zeros_like(theta)
    # The mean level profiled out; the gradient needs no term for it, since 1ᵀK⁻¹(y − level·1) = 0 at its estimate.
    k1 = Kinv.sum(axis=1)
    y = y - float(k1 @ y / k1.sum())
    alpha = cho_solve((L, True), y, check_finite=False)
    nll = 0.5 * y @ alpha + np.sum(np.log(np.diag(L))) + 0.5 * n * math.log(2 * math.pi)
    A = np.outer(alpha, alpha) - Kinv
    M = A * W
    U = X / ell
    # Σ_ij M_ij (u_ik − u_jk)² without forming the n × n × d differences.
    grad_ell = -0.5 * (2.0 * np.sum(U * U * M.sum(1)[:, None], 0) - 2.0 * np.sum(U * (M @ U), 0))
    grad = np.concatenate([grad_ell, [-0.5 * np.sum(A * Kp), -0.5 * noise * np.trace(A)]])
    if additive:
        grad[:d] -= 0.5 * weight * additive_gradient(Xc, ell, A)
        grad = np.concatenate([grad, [-0.5 * np.sum(A * Ka)]])
    # Log-normal prior on the length-scales, variance 3 (weight w: 1 with the prior, 0 for plain ML-II).
    z = theta[:d] - prior_mu
    return float(nll + w * np.sum(z * z) / 6.0), grad + w * np.concatenate([z / 3.0, np.zeros(theta.size - d)])


def fit_gp(X: np.ndarray, y: np.ndarray, rng: np.random.Generator, warm: np.ndarray | None = None,
           starts: int = 3, maxiter: int = 100, prior: bool = True, spacing_floor: bool = False,
           additive: bool = True, quadratic: bool | None = None) -> GaussianProcess:
    """Fit the hyperparameters by L-BFGS-B on the log posterior from ``starts`` points and keep the best.

    Parameters
    ----------
    X : (n, d) ndarray
        Designs in the unit cube.
    y : (n,) ndarray
        Standardised targets.
    rng : Generator
        Draws the random starts (from the prior).
    warm : ndarray, optional
        A previous fit's ``theta``, tried first (consecutive fits differ by a design or a few).
    starts : int
        Starting points of the optimiser, ``warm`` included.
    maxiter : int
        L-BFGS-B iterations per start.
    prior : bool
        Maximise the posterior with the length-scale prior (default) or the plain marginal likelihood.
    spacing_floor : bool
        When the fitted model correlates no design with its nearest neighbour (:func:`_sees_no_neighbour`), fit it
        again with no length-scale shorter than half the designs' median nearest-neighbour distance.
    additive : bool
        Fit the first-order additive component beside the product kernel (default), or the product kernel alone.
    quadratic : bool, optional
        The prior mean's form (:class:`GaussianProcess`); default: quadratic where the designs pay for it.

    Notes
    -----
    A few designs far apart can look uncorrelated, and the marginal likelihood then puts every length-scale on its
    lower bound: a model of white noise, which predicts the mean level everywhere but next to a design.  Its
    expected improvement is flat, the next design lands beside the best one, and the fit after it takes a variable
    for irrelevant: the run refines the basin of the best design of its Sobol set.  The data cannot tell a
    correlation length shorter than their own spacing from none; the floor asks for the shortest one they can
    resolve.  It applies only to a fit that sees white noise: at every fit it would hide wells narrower than the
    designs' spacing (Michalewicz) and take its share from the additive component, which shares the length-scales
    (the measurements: ``docs/guide/design-evidence.md``).
    """
    gp = _fit(X, y, rng, warm, starts, maxiter, prior, _LOG_ELL[0], additive, quadratic)
    if spacing_floor and X.shape[0] > 1 and _sees_no_neighbour(gp):
        floor = math.log(max(0.5 * _median_spacing(X), 1e-12))
        gp = _fit(X, y, rng, None, starts, maxiter, prior, min(max(_LOG_ELL[0], floor), _LOG_ELL[1]), additive,
                  quadratic)
    return gp


def _median_spacing(X: np.ndarray) -> float:
    """Median over the designs of the distance to the nearest other design (unit cube)."""
    D = np.sqrt(np.sum((X[:, None, :] - X[None, :, :]) ** 2, axis=2))
    np.fill_diagonal(D, np.inf)
    return float(np.median(D.min(axis=1)))


def _sees_no_neighbour(gp: GaussianProcess) -> bool:
    """Whether the median design's correlation with its nearest neighbour under ``gp``'s kernel is below 0.05."""
    C = gp.K / gp.K[0, 0]
    np.fill_diagonal(C, -np.inf)
    return bool(np.median(C.max(axis=1)) < _NO_NEIGHBOUR)


def _prior_mean(d: int) -> float:
    """Mean of the log length-scale prior in ``d`` variables (Hvarfner, Hellsten & Nardi 2024)."""
    return math.sqrt(2.0) + 0.5 * math.log(d)


def _fit(X: np.ndarray, y: np.ndarray, rng: np.random.Generator, warm: np.ndarray | None, starts: int,
         maxiter: int, prior: bool, log_ell_min: float, additive: bool = True,
         quadratic: bool | None = None) -> GaussianProcess:
    """:func:`fit_gp` with ``log_ell_min`` as the lower bound of every log length-scale."""
    d = X.shape[1]
    prior_mu = _prior_mean(d)
    log_ell = (log_ell_min, _LOG_ELL[1])
    bounds = [log_ell] * d + [_LOG_SIGNAL, _LOG_NOISE] + ([_LOG_ADDITIVE] if additive else [])
    lo, hi = np.array(bounds).T
    if warm is not None:
        # A previous fit that left the additive component out (below) restarts it from where it was left.
        warm = np.append(warm, _LOG_ADDITIVE[0]) if additive and warm.size == d + 2 else warm[: len(bounds)]
    cands = [] if warm is None else [np.clip(warm, lo, hi)]
    while len(cands) < max(starts, 1):
        ell = np.clip(prior_mu + math.sqrt(3.0) * rng.standard_normal(d), *log_ell)
        cands.append(np.concatenate([ell, [0.0, math.log(1e-4)] + ([_LOG_ADDITIVE_START] if additive else [])]))
    best, best_val = cands[0], np.inf
    for theta0 in cands:
        res = minimize(_neg_log_posterior, theta0, args=(X, y, prior_mu, float(prior)), jac=True, method="L-BFGS-B",
                       bounds=bounds, options={"maxiter": maxiter, "ftol": _FTOL})
        if res.fun < best_val:
            best, best_val = res.x, res.fun
    if additive and best[d + 2] < best[d] + _NEGLIGIBLE:
        # The evidence gave the additive component (next to) nothing: the model is the product kernel's, and
        # predicting without the component's d terms a pair of designs is cheaper (Hartmann-6 at 300 simulations:
        # 55 s of the method's own time instead of 65 s).
        best = best[: d + 2]
    return GaussianProcess(X, y, best, quadratic)


def noise_log_bayes_factor(gp: GaussianProcess, n: int, prior: bool, null_noise: float) -> float:
    """ln of the Bayes factor of ``gp``'s fitted white noise against a negligible one, on its first ``n`` designs.

    The model with the noise variance fixed at ``null_noise`` (every other hyperparameter fitted again, from
    ``gp``'s) is the near-interpolating one a deterministic simulator deserves; its log posterior is compared with
    ``gp``'s.  A smooth function that the kernel fits imperfectly buys a little noise for a few nats; values that
    scatter from design to design cannot be interpolated without length-scales shorter than the designs' spacing,
    and lose many.  The null is a small noise rather than the floor: designs a hair apart (a polish beside the
    incumbent) leave the covariance singular to rounding at the floor, and a failed factorisation would count as
    evidence for noise.

    Parameters
    ----------
    gp : GaussianProcess
        A fitted model (:func:`fit_gp`).
    n : int
        Its leading designs the factor is measured on (the designs that were simulated, not imputed).
    prior : bool
        Whether ``gp`` was fitted with the length-scale prior.
    null_noise : float
        Noise variance of the model without noise (standardised values).
    """
    X, y = gp.X[:n], gp.y[:n]
    d = X.shape[1]
    prior_mu = _prior_mean(d)
    theta = gp.theta if gp.theta.size > d + 2 else np.append(gp.theta, _LOG_ADDITIVE[0])
    fitted = _neg_log_posterior(theta, X, y, prior_mu, float(prior))[0]
    log_null = math.log(null_noise)
    bounds = [_LOG_ELL] * d + [_LOG_SIGNAL, (log_null, log_null), _LOG_ADDITIVE]
    start = theta.copy()
    start[d + 1] = log_null
    res = minimize(_neg_log_posterior, start, args=(X, y, prior_mu, float(prior)), jac=True, method="L-BFGS-B",
                   bounds=bounds, options={"maxiter": 100, "ftol": _FTOL})
    return float(min(res.fun, _neg_log_posterior(start, X, y, prior_mu, float(prior))[0]) - fitted)
