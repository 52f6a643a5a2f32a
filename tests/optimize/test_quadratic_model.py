"""The full quadratic model of the default method's trust-region steps against known answers."""

import numpy as np
from scipy.stats import special_ortho_group

from mechopt.optimize.auto.quadratic_model import fit_quadratic, n_coefficients


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


def test_least_frobenius_interpolates_and_matches_the_closed_form():
    # d + 2 designs in 2-D: the interpolant whose Hessian has the least Frobenius norm, checked against a direct
    # minimisation of that norm over every interpolating quadratic (scipy's SLSQP on the 6 coefficients).
    from scipy.optimize import minimize

    rng = np.random.default_rng(3)
    d, centre = 2, np.array([0.4, 0.6])
    U = centre + 0.2 * rng.uniform(-1, 1, (4, d))
    f = np.sin(3 * U[:, 0]) + U[:, 1] ** 3
    model = fit_quadratic(U, f, centre)
    np.testing.assert_allclose(model(U), f, atol=1e-10)

    def interp(c):
        S = U - centre
        return c[0] + S @ c[1:3] + 0.5 * (c[3] * S[:, 0] ** 2 + 2 * c[4] * S[:, 0] * S[:, 1] + c[5] * S[:, 1] ** 2) - f

    res = minimize(lambda c: c[3] ** 2 + 2 * c[4] ** 2 + c[5] ** 2, np.zeros(6), method="SLSQP",
                   constraints=[{"type": "eq", "fun": interp}], options={"ftol": 1e-14, "maxiter": 500})
    np.testing.assert_allclose(model.hessian, [[res.x[3], res.x[4]], [res.x[4], res.x[5]]], atol=1e-6)


def test_too_few_designs_give_no_model():
    assert fit_quadratic(np.zeros((2, 3)), np.zeros(2), np.zeros(3)) is None
    # d + 1 designs on a line fix no linear model.
    U = np.outer(np.linspace(0, 1, 4), np.ones(3))
    assert fit_quadratic(U, np.arange(4.0), U[0]) is None
