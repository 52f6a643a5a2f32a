"""The full quadratic model of the default method's trust-region steps against known answers."""

import numpy as np
import pytest
from scipy.stats import special_ortho_group

from mechopt.optimize.auto.quadratic_model import fit_quadratic, leave_one_out_r2, n_coefficients


def _rotated_quadratic(d: int, seed: int):
    rng = np.random.default_rng(seed)
    Q = special_ortho_group.rvs(d, random_state=rng)
    H = Q @ np.diag(10.0 ** np.linspace(0, 6, d)) @ Q.T
    xs = rng.uniform(0.2, 0.8, d)
    return H, xs, lambda U: 0.5 * np.sum(((U - xs) @ H) * (U - xs), axis=1) + 3.0


def test_least_squares_recovers_a_rotated_ill_conditioned_hessian():
    d = 5
    H, xs, f = _rotated_quadratic(d, 1)
    rng = np.random.default_rng(2)
    centre = np.full(d, 0.5)
    U = centre + 0.05 * rng.uniform(-1, 1, (n_coefficients(d) + 4, d))
    model = fit_quadratic(U, f(U), centre)
    np.testing.assert_allclose(model.hessian, H, rtol=1e-6, atol=1e-6 * np.abs(H).max())
    # The minimiser of the model in a box holding the optimum is the optimum.
    x = model.minimiser(np.zeros(d), np.ones(d))
    np.testing.assert_allclose(x, xs, atol=1e-6)
    np.testing.assert_allclose(model(U), f(U), rtol=1e-8)


def test_leave_one_out_r2_matches_refits_and_tells_a_quadratic_from_noise():
    d = 3
    H, xs, f = _rotated_quadratic(d, 4)
    rng = np.random.default_rng(5)
    centre = np.full(d, 0.5)
    U = centre + 0.3 * rng.uniform(-1, 1, (2 * n_coefficients(d), d))
    assert leave_one_out_r2(U, f(U), centre) == pytest.approx(1.0, abs=1e-9)
    noise = rng.random(U.shape[0])
    # The closed form against brute force: each design left out of its own least-squares refit.
    loo = []
    for i in range(U.shape[0]):
        keep = np.arange(U.shape[0]) != i
        loo.append(noise[i] - fit_quadratic(U[keep], noise[keep], centre)(U[i:i + 1])[0])
    brute = 1.0 - np.sum(np.square(loo)) / np.sum((noise - noise.mean()) ** 2)
    assert leave_one_out_r2(U, noise, centre) == pytest.approx(brute, rel=1e-8)
    assert brute < 0.0
    assert np.isnan(leave_one_out_r2(U[: n_coefficients(d)], noise[: n_coefficients(d)], centre))


def test_too_few_designs_give_no_model():
    assert fit_quadratic(np.zeros((9, 3)), np.zeros(9), np.zeros(3)) is None
    # Designs on a line fix no linear model in 3 variables.
    U = np.outer(np.linspace(0, 1, 12), np.ones(3))
    assert fit_quadratic(U, np.arange(12.0), U[0]) is None
