"""The probability that a design meets the limits on its simulated outputs: one Gaussian process per limited output.

Each limited output g_j gets a GP of its standardised values (:func:`~mechopt.optimize.auto.gp.fit_gp`, the default
method's model); a design meets limit j with probability Φ((upper − μ)/σ) − Φ((lower − μ)/σ), and the limits are
taken as independent, so log P(meets every limit) is the sum over j.  Multiplied into the expected improvement, this
is the constrained expected improvement of Schonlau, Welch & Jones (1998) and Gardner et al. (2014): a simulated
design that breaks a limit still teaches its output's model where the limit lies.
"""

from __future__ import annotations

import numpy as np
from scipy.special import log_ndtr, ndtr

from mechopt.optimize.auto.gp import GaussianProcess, fit_gp

__all__ = ["LimitModels"]

#: Floor of a probability before its logarithm is taken (a design far outside a limit still ranks by how far).
_TINY = 1e-300


class LimitModels:
    """GPs of the limited outputs, refitted as designs arrive (warm-started from the previous fit).

    Parameters
    ----------
    lower, upper : (m,) ndarray
        The limits, in the outputs' units (-inf / +inf where open).
    """

    def __init__(self, lower: np.ndarray, upper: np.ndarray) -> None:
        self.lower, self.upper = np.asarray(lower, float), np.asarray(upper, float)
        self._theta: list[np.ndarray | None] = [None] * self.lower.size
        self._fitted_n = [0] * self.lower.size
        self._models: list[tuple[GaussianProcess, float, float]] = []

    @property
    def m(self) -> int:
        """Number of limited outputs."""
        return self.lower.size

    def fit(self, U: np.ndarray, G: np.ndarray, rng: np.random.Generator) -> None:
        """Fit each output's GP to designs U (n, d, unit cube) and their outputs G (n, m), all finite."""
        self._models = []
        for j in range(self.m):
            g = G[:, j]
            mu, sd = float(np.mean(g)), float(np.std(g)) or 1.0
            # A full fit from several starts when the designs have grown by a quarter; otherwise a short warm one.
            full = self._theta[j] is None or U.shape[0] >= 1.25 * self._fitted_n[j]
            if full:
                self._fitted_n[j] = U.shape[0]
            gp = fit_gp(U, (g - mu) / sd, rng, warm=self._theta[j], starts=3 if full else 1,
                        maxiter=100 if full else 30, prior=False, spacing_floor=True)
            self._theta[j] = gp.theta
            self._models.append((gp, mu, sd))

    def log_probability(self, U: np.ndarray) -> np.ndarray:
        """log P(every limit met) at designs U (q, d) of the unit cube."""
        U = np.atleast_2d(U)
        total = np.zeros(U.shape[0])
        for (gp, mu, sd), lo, hi in zip(self._models, self.lower, self.upper, strict=True):
            mean, s = gp.predict(U)
            a, b = (lo - mu) / sd, (hi - mu) / sd
            za, zb = (a - mean) / s, (b - mean) / s
            if not np.isfinite(lo):
                total += log_ndtr(zb)
            elif not np.isfinite(hi):
                total += log_ndtr(-za)
            else:
                total += np.log(np.maximum(ndtr(zb) - ndtr(za), _TINY))
        return total
