"""The probability that a design meets the limits on its simulated outputs: one Gaussian process per limited output.

Each limited output g_j gets a GP of its standardised values
(:class:`~mechopt.optimize.auto.output_models.OutputModels`, the default method's model); a design meets limit j
with probability Φ((upper − μ)/σ) − Φ((lower − μ)/σ), and the limits are taken as independent, so
log P(meets every limit) is the sum over j.  Multiplied into the expected improvement, this is the constrained
expected improvement of Schonlau, Welch & Jones (1998) and Gardner et al. (2014): a simulated design that breaks a
limit still teaches its output's model where the limit lies.
"""

from __future__ import annotations

import numpy as np
from scipy.special import log_ndtr, ndtr

from mechopt.optimize.auto.output_models import OutputModels

__all__ = ["LimitModels"]

#: Floor of a probability before its logarithm is taken (a design far outside a limit still ranks by how far).
_TINY = 1e-300


class LimitModels:
    """The limited outputs' GPs (:class:`~mechopt.optimize.auto.output_models.OutputModels`) and their limits.

    Parameters
    ----------
    lower, upper : (m,) ndarray
        The limits, in the outputs' units (-inf / +inf where open).
    prior : bool
        Fit the outputs' GPs with the length-scale prior (:class:`OutputModels`).
    """

    def __init__(self, lower: np.ndarray, upper: np.ndarray, prior: bool = False) -> None:
        self.lower, self.upper = np.asarray(lower, float), np.asarray(upper, float)
        self._outputs = OutputModels(self.lower.size, prior)

    @property
    def m(self) -> int:
        """Number of limited outputs."""
        return self.lower.size

    def met(self, G: np.ndarray) -> np.ndarray:
        """Designs (n,) whose limited outputs G (n, m) lie within every limit."""
        return np.all((G >= self.lower) & (G <= self.upper), axis=1)

    def fit(self, U: np.ndarray, G: np.ndarray, rng: np.random.Generator) -> None:
        """Fit each output's GP to designs U (n, d, unit cube) and their outputs G (n, m), all finite."""
        self._outputs.fit(U, G, rng)

    def log_probability(self, U: np.ndarray) -> np.ndarray:
        """log P(every limit met) at designs U (q, d) of the unit cube."""
        U = np.atleast_2d(U)
        total = np.zeros(U.shape[0])
        if not self.m:
            return total
        mean, s = self._outputs.predict(U)
        for j, (lo, hi) in enumerate(zip(self.lower, self.upper, strict=True)):
            za, zb = (lo - mean[:, j]) / s[:, j], (hi - mean[:, j]) / s[:, j]
            if not np.isfinite(lo):
                total += log_ndtr(zb)
            elif not np.isfinite(hi):
                total += log_ndtr(-za)
            else:
                total += np.log(np.maximum(ndtr(zb) - ndtr(za), _TINY))
        return total
