"""The GP's targets (``optimize/auto/transform.py``): monotone, standardised, and power-transformed only where the
values call for it."""

import numpy as np
from scipy.stats import skew, yeojohnson_normmax

from mechopt.optimize.auto.transform import gaussianise, standardise


def _scaled(v):
    return (v - np.median(v)) / np.std(v)


def test_gaussian_values_are_only_centred_and_scaled():
    v = np.random.default_rng(0).normal(3.0, 2.0, 200)
    np.testing.assert_array_equal(gaussianise(v), _scaled(v))


def test_a_long_upper_tail_gets_the_maximum_likelihood_exponent():
    v = np.exp(np.random.default_rng(1).normal(0.0, 1.0, 200))  # log-normal: the log is the Gaussianising map
    g = gaussianise(v)
    assert np.array_equal(np.argsort(g), np.argsort(v))  # monotone: the ranking, and so the incumbent, is kept
    assert abs(skew(g)) < 0.2 < skew(v)
    # scipy's own maximum-likelihood exponent of the same scaled values, inside the range searched
    from scipy.stats import yeojohnson

    lam = yeojohnson_normmax(_scaled(v))
    assert -3.0 < lam < 1.0
    np.testing.assert_allclose(g, yeojohnson(_scaled(v), lmbda=lam), atol=1e-3)


def test_a_long_lower_tail_is_not_compressed():
    # The few deep designs a minimiser resolves: a power above 1 would pull them toward the rest.
    v = -np.exp(np.random.default_rng(2).normal(0.0, 1.0, 200))
    np.testing.assert_array_equal(gaussianise(v), _scaled(v))


def test_too_few_or_equal_values_are_left_as_they_are():
    for v in (np.array([1.0, 5.0]), np.full(6, 2.5)):
        np.testing.assert_array_equal(gaussianise(v), v)


def test_global_targets_are_standardised_and_in_order():
    v = np.exp(np.random.default_rng(3).normal(0.0, 2.0, 40))
    y = standardise(v, compress_tail=False)
    assert abs(y.mean()) < 1e-12 and abs(y.std() - 1.0) < 1e-12
    assert np.array_equal(np.argsort(y), np.argsort(v))
