"""The answer of the default method: the simulated design the model believes lowest, which on a noisy simulator is
not the one whose simulation came out lowest.

A simulator with numerical noise (a time step, a mesh, a contact tolerance: deterministic, but rough in the design)
returns values scattered about the objective; of a few hundred designs the lowest value is the one whose noise came
out most negative, and its design is a lucky draw more than a good one.  The GP fitted to the designs estimates the
noise (its white-noise variance, by the same marginal likelihood as the length-scales) and its posterior mean at a
simulated design is the objective smoothed over its neighbours; the design of lowest mean is the better answer
(the in-sample "best point" of noisy Bayesian optimisation: Letham, Karrer, Ottoni & Bakshy 2019; BoTorch and Ax
report it).  The measurements behind this module's choices: ``docs/guide/design-evidence.md``.

A deterministic simulator keeps the lowest value simulated as its answer.  Mostly its fitted noise sits at the
numerical floor, and the mean at a design is its value.  Where the kernel fits the function imperfectly the fit may
buy a little noise (cosine_bowl3 at 30 simulations, seed 5: a noise sd of 0.6 % of the values', and an answer
0.011 % of the range above the lowest value), so the noise must also earn its place: the evidence for it against
the near-interpolating model (a noise variance of ``NOISE_THRESHOLD``, every other hyperparameter fitted again)
must be strong, a Bayes factor above e^3 ≈ 20 (2 ln B > 6, Kass & Raftery 1995).
"""

from __future__ import annotations

import numpy as np

from mechopt.optimize.auto.gp import GaussianProcess, noise_log_bayes_factor

__all__ = ["NOISE_THRESHOLD", "STRONG_EVIDENCE", "lowest_mean"]

#: White-noise variance of the standardised values (the noise's share of their variance) above which the simulator
#: is taken for noisy.  Below it the noise's sd is under 0.1 % of the values' spread: the ranking of designs by
#: value is then the model's to that precision, and a deterministic simulator (fitted noise 1e-10) keeps its lowest
#: value as the answer exactly.
NOISE_THRESHOLD = 1e-6
#: ln of the Bayes factor for the fitted noise against none above which the simulator is taken for noisy.
STRONG_EVIDENCE = 3.0


def lowest_mean(gp: GaussianProcess, U: np.ndarray, candidates: np.ndarray, best: int, prior: bool) -> int:
    """Index (into ``U``) of the design of lowest posterior mean among ``candidates``, or ``best`` unless the
    simulator is noisy: the model's noise above :data:`NOISE_THRESHOLD` and its evidence above
    :data:`STRONG_EVIDENCE`.

    Parameters
    ----------
    gp : GaussianProcess
        Fitted to the designs (unit cube) around the incumbent, the ``candidates`` first, in their order.
    U : (n, d) ndarray
        Every design simulated (unit cube).
    candidates : (m,) int ndarray
        Indices of the designs that may be the answer (simulated successfully, inside the model's reach).
    best : int
        Index of the design of lowest simulated value.
    prior : bool
        Whether ``gp`` was fitted with the length-scale prior.
    """
    if candidates.size == 0 or gp.noise <= NOISE_THRESHOLD:
        return int(best)
    if noise_log_bayes_factor(gp, candidates.size, prior, NOISE_THRESHOLD) < STRONG_EVIDENCE:
        return int(best)
    mean, _ = gp.predict(U[candidates])
    return int(candidates[int(np.argmin(mean))])
