"""The hidden constraint of failed simulations: a model of where the simulator succeeds, learned from the designs
that succeeded (label +1) and failed (label −1).

A GP regression on the labels (Matérn-5/2 with the objective model's length-scales, the labels' mean as prior mean)
gives a latent score; the probability of success is Φ(score / √(σ² + s²)), s² = 0.1 blurring the ±1 labels into a
soft boundary.  Far from every design the score returns to the labels' mean: a region is avoided only where failures
were seen, in proportion to how close they are.  Cheap (one Cholesky of the n labels), refitted at every step.
"""

from __future__ import annotations

import numpy as np
from scipy.special import log_ndtr

from mechopt.optimize.auto.gp import GaussianProcess

__all__ = ["SuccessModel"]

#: Variance added to the label model's own: the ±1 labels are a step, not a smooth function.
_LABEL_BLUR = 0.1
#: Noise variance of the labels (a design may fail for reasons the model cannot see).
_LABEL_NOISE = 0.05


class SuccessModel:
    """Probability that the simulation of a design succeeds.

    Parameters
    ----------
    X : (n, d) ndarray
        Every simulated design (unit cube).
    succeeded : (n,) bool ndarray
        Whether each simulation returned a finite value.
    log_ell : (d,) ndarray
        Log length-scales (the objective model's).
    """

    def __init__(self, X: np.ndarray, succeeded: np.ndarray, log_ell: np.ndarray) -> None:
        labels = np.where(succeeded, 1.0, -1.0)
        self.prior = float(labels.mean())
        theta = np.concatenate([log_ell, [0.0, np.log(_LABEL_NOISE)]])
        # A constant mean: the labels are a step, and a quadratic trend would carry a failing region across the box.
        self.gp = GaussianProcess(X, labels - self.prior, theta, quadratic=False)

    def log_probability(self, U: np.ndarray) -> np.ndarray:
        """log P(success) at designs U (m, d)."""
        mean, sd = self.gp.predict(U)
        return log_ndtr((mean + self.prior) / np.sqrt(sd * sd + _LABEL_BLUR))
