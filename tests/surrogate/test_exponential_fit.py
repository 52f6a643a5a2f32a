"""1-D exponential fitting: exact recovery, order selection, noise, negative nodes, bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mechopt.surrogate import ExponentialFit, SurrogateError, SurrogateWarning, fit_exponential

METHODS = [("matrix_pencil", "ls"), ("matrix_pencil", "tls"), ("esprit", "ls"), ("esprit", "tls")]

# (nodes z_j, coefficients β_j) of exponential sums T_k = Σ β_j z_j^k.
CASES = {
    "real": (np.array([0.9, 0.5, 1.05]), np.array([1.0, 0.7, -0.4])),
    "damped_oscillatory": (
        np.array([0.95 * np.exp(0.6j), 0.95 * np.exp(-0.6j), 0.8]),
        np.array([0.5 + 0.2j, 0.5 - 0.2j, 1.0]),
    ),
    "close_exponents": (np.exp(-np.array([0.10, 0.11, 0.12])), np.array([1.0, 0.7, -0.4])),
}


def exp_sum(nodes, coefs, k):
    k = np.asarray(k, dtype=float)
    return (np.exp(np.multiply.outer(k, np.log(nodes.astype(complex)))) @ coefs.astype(complex)).real


@pytest.mark.parametrize("method,solver", METHODS)
@pytest.mark.parametrize("case", list(CASES))
def test_exact_recovery_from_2n_samples(case, method, solver):
    nodes, coefs = CASES[case]
    n = nodes.size
    y = exp_sum(nodes, coefs, np.arange(2 * n))
    fit = fit_exponential(y, order=n, method=method, solver=solver)
    k = np.linspace(-1.0, 2 * n + 1.0, 97)  # real k, including a little extrapolation
    truth = exp_sum(nodes, coefs, k)
    # Tolerance: 1e-9 of the data scale for the function; nodes to 1e-9, or 1e-6 for exponents 0.01 apart
    # (from 6 samples their separation is ill-conditioned while the function itself is not).
    assert np.max(np.abs(fit(k) - truth)) <= 1e-9 * np.max(np.abs(truth))
    node_tol = 1e-6 if case == "close_exponents" else 1e-9
    assert np.max(np.abs(np.sort_complex(fit.nodes) - np.sort_complex(nodes.astype(complex)))) <= node_tol
    assert fit.order == n and fit.rms_residual <= 1e-12


@pytest.mark.parametrize("method,solver", METHODS)
@pytest.mark.parametrize("case", list(CASES))
def test_automatic_order_on_clean_data_is_the_true_one(case, method, solver):
    nodes, coefs = CASES[case]
    for n_samples in (12, 40, 90):
        fit = fit_exponential(exp_sum(nodes, coefs, np.arange(n_samples)), method=method, solver=solver)
        assert fit.order == nodes.size, (n_samples, fit.message)


@pytest.mark.parametrize("n_true", [1, 2, 4, 5])
def test_automatic_order_other_sizes(n_true):
    rng = np.random.default_rng(n_true)
    nodes = np.exp(rng.uniform(-0.15, 0.05, n_true))
    coefs = rng.uniform(0.5, 1.5, n_true)
    fit = fit_exponential(exp_sum(nodes, coefs, np.arange(60)))
    assert fit.order == n_true, fit.message


@pytest.mark.parametrize("method,solver", METHODS)
def test_noise_gives_errors_of_the_order_of_the_noise(method, solver):
    # 1e-4 relative noise on a class member and on smooth positive curves outside the class; the fitted curve,
    # evaluated between the samples too, must stay within 5x the noise level of the truth.
    n_samples = 60
    k = np.arange(n_samples)
    kk = np.linspace(0, n_samples - 1, 400)
    nodes, coefs = CASES["real"]
    curves = {
        "class": lambda x: exp_sum(nodes, coefs, x) + 2.0,
        "hyperbola": lambda x: 2.0 * np.sqrt(1.0 + ((x - 25.0) / 12.0) ** 2),
        "rational": lambda x: 1.0 / (1.0 + 0.5 * (x / 60.0) ** 2) + 0.3 * x / 60.0,
    }
    for name, curve in curves.items():
        for seed in range(3):
            rng = np.random.default_rng(seed)
            y = curve(k) * (1.0 + 1e-4 * rng.standard_normal(n_samples))
            fit = fit_exponential(y, method=method, solver=solver)
            err = np.max(np.abs(fit(kk) - curve(kk))) / np.max(np.abs(curve(kk)))
            assert err <= 5e-4, (name, seed, err, fit.message)
            assert not fit.has_negative_nodes, (name, seed)


def test_values_are_real_and_pairs_conjugate():
    nodes, coefs = CASES["damped_oscillatory"]
    fit = fit_exponential(exp_sum(nodes, coefs, np.arange(30)))
    z, b = fit.nodes, fit.coefficients
    for j in np.flatnonzero(z.imag > 0):
        partner = np.argmin(np.abs(z - np.conj(z[j])))
        assert b[partner] == np.conj(b[j])
    out = fit(np.array([[0.25, 1.5], [2.75, 10.1]]))
    assert out.shape == (2, 2) and out.dtype == float


def test_derivative_matches_finite_differences():
    nodes, coefs = CASES["damped_oscillatory"]
    fit = fit_exponential(exp_sum(nodes, coefs, np.arange(30)))
    k = np.linspace(0.3, 25.0, 11)
    h = 1e-5
    fd = (fit(k + h) - fit(k - h)) / (2 * h)
    assert np.max(np.abs(fit.derivative(k) - fd)) <= 1e-7


def test_forced_order_with_negative_node_warns_and_interpolates():
    # (−0.6)^k is an oscillation at Nyquist: kept when the caller forces the order, with a warning.
    nodes = np.array([0.9, -0.6])
    coefs = np.array([1.0, 0.3])
    y = exp_sum(nodes, coefs, np.arange(12))
    with pytest.warns(SurrogateWarning, match="negative real node"):
        fit = fit_exponential(y, order=2)
    assert fit.has_negative_nodes and "negative real node" in fit.message
    assert np.max(np.abs(fit(np.arange(12)) - y)) <= 1e-10
    half = np.array([0.5, 3.5])
    expected = 0.9**half + 0.3 * 0.6**half * np.cos(np.pi * half)
    assert np.max(np.abs(fit(half) - expected)) <= 1e-10


def test_automatic_order_avoids_negative_nodes():
    nodes = np.array([0.9, -0.6])
    coefs = np.array([1.0, 1e-3])  # a tiny Nyquist component, like noise
    y = exp_sum(nodes, coefs, np.arange(40)) + 2.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = fit_exponential(y)
    assert not fit.has_negative_nodes


def test_zero_data_gives_empty_model():
    fit = fit_exponential(np.zeros(10))
    assert fit.order == 0 and np.all(fit(np.array([0.5, 3.0])) == 0.0)


def test_round_trip_through_dict():
    nodes, coefs = CASES["damped_oscillatory"]
    fit = fit_exponential(exp_sum(nodes, coefs, np.arange(30)))
    again = ExponentialFit.from_dict(fit.to_dict())
    k = np.linspace(0, 29, 50)
    assert np.array_equal(again(k), fit(k)) and again.order == fit.order


@pytest.mark.parametrize(
    "values,kwargs,pattern",
    [
        (np.ones(7), {"order": 4}, r"2n = 8 samples, got N = 7"),
        (np.array([1.0, 2.0, 3.0, np.nan, 5.0]), {}, r"sample 3 is nan"),
        (np.array([1.0, np.inf, 3.0]), {}, r"sample 1 is inf"),
        (np.ones(1), {}, r"at least 2 samples"),
        (np.ones((3, 3)), {}, r"1-D"),
        (np.ones(10), {"order": 0}, r"positive integer"),
        (np.ones(10), {"method": "prony"}, r"method must be one of"),
        (np.ones(10), {"solver": "svd"}, r"solver must be one of"),
    ],
)
def test_bad_input_raises_one_line_error(values, kwargs, pattern):
    with pytest.raises(SurrogateError, match=pattern) as info:
        fit_exponential(values, **kwargs)
    assert "\n" not in str(info.value)
