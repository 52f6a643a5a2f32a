"""The GP's prior mean: a constant, or a quadratic without cross terms where the designs pay for it, estimated by
generalised least squares at the fitted covariance (universal kriging; DACE's and SMT's ``poly`` options).

A designer's objective is often a bowl with detail on it: a second-order response surface is the first model of
response-surface methodology, and a design problem's optimum sits at the bottom of some such bowl or against a
bound it leans on.  A stationary GP with a constant mean knows nothing of the bowl: away from the designs it
reverts to the level, its variance grows toward the faces, and expected improvement spends the budget on faces and
corners while the bowl's bottom, between the designs, looks like the level.  A quadratic trend extrapolates the
bowl there, and the GP models the detail on it.

But not every landscape is a bowl.  The trend is each variable's linear and square term (2d + 1 coefficients; the
d(d − 1)/2 cross terms would need as many designs as a full quadratic response surface), and it replaces the
constant only when there are :data:`DESIGNS_PER_TERM` designs a coefficient and the Bayesian information criterion
prefers it: its 2d terms must reduce the residuals' squared Mahalanobis norm under the fitted covariance by more
than 2d·log n.  The covariance's hyperparameters are fitted under the constant mean, and the trend chosen at them
afterwards, in the order of blind kriging (Joseph, Hung & Sudjianto 2008): profiled out of the evidence, the
trend's coefficients would leave the length-scales fitted to what an over-fitted trend left.  The trend's own
uncertainty is left out of the variance, as the constant level's is (:mod:`~mechopt.optimize.auto.gp`).

The criterion is what keeps the constant on landscapes that are no bowl (Schwefel, Michalewicz), which a trend
always taken misleads.  The measurements: ``docs/guide/design-evidence.md``; suite, peers and budgets up to 500:
BENCHMARKS.md.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import cho_solve

__all__ = ["DESIGNS_PER_TERM", "Trend"]

#: Designs a coefficient of the quadratic trend needs before it replaces the constant: twice, the least for a
#: regression to have as many degrees of freedom left as it spends.
DESIGNS_PER_TERM = 2


class Trend:
    """The GLS prior mean of a GP at its designs.

    Parameters
    ----------
    X : (n, d) ndarray
        Designs (unit cube).
    y : (n,) ndarray
        Targets.
    L : (n, n) ndarray
        Lower Cholesky factor of the designs' covariance (noise included).
    quadratic : bool, optional
        Quadratic (each variable's linear and square term) or constant; default: quadratic when there are
        :data:`DESIGNS_PER_TERM` designs for each of its 2d + 1 coefficients and the information criterion prefers
        it (the module's docstring).
    """

    def __init__(self, X: np.ndarray, y: np.ndarray, L: np.ndarray, quadratic: bool | None = None) -> None:
        n, d = X.shape
        # Centred and scaled on the designs: 1, z and z² are then far from collinear even in a small trust region.
        self.centre = X.mean(axis=0) if n else np.zeros(d)
        spread = X.std(axis=0) if n else np.ones(d)
        self.scale = np.where(spread > 1e-12, spread, 1.0)
        if quadratic is None and n >= DESIGNS_PER_TERM * (2 * d + 1):
            # The Bayesian information criterion: the 2d terms must reduce the residuals' squared Mahalanobis norm
            # by more than 2d·log n (twice the log-likelihood's price of 2d parameters).
            beta_constant, misfit_constant = self._gls(X, y, L, False)
            beta_quadratic, misfit_quadratic = self._gls(X, y, L, True)
            self.quadratic = bool(misfit_constant - misfit_quadratic > 2 * d * np.log(n))
            self.beta = beta_quadratic if self.quadratic else beta_constant
        else:
            self.quadratic = bool(quadratic)
            self.beta = self._gls(X, y, L, self.quadratic)[0]

    def _gls(self, X: np.ndarray, y: np.ndarray, L: np.ndarray, quadratic: bool) -> tuple[np.ndarray, float]:
        """GLS coefficients of the constant or quadratic basis and the residual's squared Mahalanobis norm."""
        F = self._regressors(X, quadratic)
        KiF = cho_solve((L, True), F, check_finite=False)
        # Least squares: a variable every design shares (all on one face) leaves its columns at zero, and the
        # minimum-norm solution gives them no weight.
        beta = np.linalg.lstsq(F.T @ KiF, KiF.T @ y, rcond=1e-12)[0]
        r = y - F @ beta
        return beta, float(r @ cho_solve((L, True), r, check_finite=False))

    def _regressors(self, U: np.ndarray, quadratic: bool) -> np.ndarray:
        U = np.atleast_2d(U)
        if not quadratic:
            return np.ones((U.shape[0], 1))
        Z = (U - self.centre) / self.scale
        return np.hstack([np.ones((U.shape[0], 1)), Z, Z * Z])

    def basis(self, U: np.ndarray) -> np.ndarray:
        """The trend's regressors at designs U (m, d): 1, or 1, z_k and z_k² with z the centred, scaled U."""
        return self._regressors(U, self.quadratic)

    def __call__(self, U: np.ndarray) -> np.ndarray:
        """The prior mean at designs U (m, d)."""
        return self.basis(U) @ self.beta
