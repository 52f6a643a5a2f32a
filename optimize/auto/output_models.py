"""One Gaussian process per simulated output (an objective or a limited output), refitted as designs arrive.

The trade-off search models each output on its own (the objectives of the expected hypervolume improvement, the
limited outputs of the probability of meeting the limits), with the default method's model
(:func:`~mechopt.optimize.auto.gp.fit_gp`) on the output's z-score.  Outputs are taken as independent: the
acquisitions that use them factorise over outputs, which is what keeps them closed-form.
"""

from __future__ import annotations

import numpy as np

from mechopt.optimize.auto.gp import GaussianProcess, fit_gp

__all__ = ["OutputModels"]


class OutputModels:
    """GPs of ``m`` outputs, warm-started from the previous fit.

    Parameters
    ----------
    m : int
        Number of outputs.
    prior : bool
        Fit with the length-scale prior of :func:`~mechopt.optimize.auto.gp.fit_gp` (the trade-off search's choice
        when the problem declares its objectives' scale, :mod:`~mechopt.optimize.auto.multi_objective`), or by
        plain marginal likelihood with the spacing floor (default).
    """

    def __init__(self, m: int, prior: bool = False) -> None:
        self.m, self.prior = int(m), bool(prior)
        self._theta: list[np.ndarray | None] = [None] * self.m
        self._fitted_n = [0] * self.m
        self.models: list[tuple[GaussianProcess, float, float]] = []

    def fit(self, U: np.ndarray, Y: np.ndarray, rng: np.random.Generator) -> None:
        """Fit each output's GP to designs U (n, d, unit cube) and their outputs Y (n, m), all finite."""
        self.models = []
        for j in range(self.m):
            y = Y[:, j]
            mu, sd = float(np.mean(y)), float(np.std(y)) or 1.0
            # A full fit from several starts when the designs have grown by a quarter; otherwise a short warm one
            # (a fit from three starts at every design would be most of the method's time).
            full = self._theta[j] is None or U.shape[0] >= 1.25 * self._fitted_n[j]
            if full:
                self._fitted_n[j] = U.shape[0]
            gp = fit_gp(U, (y - mu) / sd, rng, warm=self._theta[j], starts=3 if full else 1,
                        maxiter=100 if full else 30, prior=self.prior, spacing_floor=not self.prior)
            self._theta[j] = gp.theta
            self.models.append((gp, mu, sd))

    def predict(self, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean and standard deviation (q, m) of every output at designs U (q, d), in the outputs' units."""
        U = np.atleast_2d(U)
        mean, sd = np.empty((U.shape[0], self.m)), np.empty((U.shape[0], self.m))
        for j, (gp, mu, scale) in enumerate(self.models):
            m_j, s_j = gp.predict(U)
            mean[:, j], sd[:, j] = mu + scale * m_j, scale * s_j
        return mean, sd
