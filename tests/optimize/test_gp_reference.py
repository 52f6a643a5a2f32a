"""The shared Gaussian process (optimize.auto.gp) against scikit-learn's on the plain case: constant mean, the
Matérn-5/2 product kernel alone, the same fixed hyperparameters.

scikit-learn's regressor has a zero prior mean; ordinary kriging's constant is estimated here by generalised least
squares on scikit-learn's own kernel matrix and subtracted from the targets first.  With the level taken as known (as
gp.py does), the two posterior means and standard deviations are the same numbers.
"""

from __future__ import annotations

import numpy as np
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import ConstantKernel, Matern

from mechopt.optimize.auto.gp import GaussianProcess


def test_plain_gp_predicts_as_scikit_learns_kriging_with_the_same_hyperparameters() -> None:
    rng = np.random.default_rng(4)
    X, U = rng.random((30, 3)), rng.random((200, 3))
    y = np.sin(5.0 * X[:, 0]) + X[:, 1] * X[:, 2] - 0.5 * X[:, 2] ** 2
    ell, signal, noise = np.array([0.35, 0.6, 0.9]), 1.7, 1e-6
    gp = GaussianProcess(X, y, np.log(np.concatenate([ell, [signal, noise]])), quadratic=False)

    kernel = ConstantKernel(signal, "fixed") * Matern(ell, "fixed", nu=2.5)
    K = kernel(X) + noise * np.eye(len(X))
    ones = np.ones(len(X))
    level = ones @ np.linalg.solve(K, y) / (ones @ np.linalg.solve(K, ones))
    reference = GaussianProcessRegressor(kernel, alpha=noise, optimizer=None).fit(X, y - level)
    mean_ref, std_ref = reference.predict(U, return_std=True)

    mean, std = gp.predict(U)
    assert std_ref.min() > 1e-2  # the comparison points are away from the designs: a relative test is meaningful
    np.testing.assert_allclose(mean, mean_ref + level, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(std, std_ref, rtol=1e-6)
