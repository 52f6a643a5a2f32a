"""The closed-form expected hypervolume improvement against moocore's hypervolume: exactly in the deterministic
limit, and against a Monte Carlo average of exact improvements for Gaussian objectives."""

import moocore
import numpy as np
import pytest

from mechopt.optimize.auto.hypervolume_improvement import (
    BoxDecomposition,
    expected_improvement,
    hypervolume_improvement,
)
from mechopt.optimize.pareto import front_mask


def _front(k: int, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    Z = np.abs(rng.standard_normal((n, k)))
    P = Z / np.linalg.norm(Z, axis=1)[:, None]  # points of the unit sphere's positive orthant: all non-dominated
    return P[front_mask(P)]


def _exact_improvement(P: np.ndarray, Y: np.ndarray, ref: np.ndarray) -> np.ndarray:
    base = moocore.hypervolume(P, ref=ref)
    return np.array([moocore.hypervolume(np.vstack([P, y]), ref=ref) - base if np.all(y < ref) else 0.0 for y in Y])


@pytest.mark.parametrize("k", [2, 3, 4])
def test_improvement_of_points_matches_moocore(k):
    P, ref = _front(k, 12, k), np.full(k, 1.1)
    Y = np.random.default_rng(10 + k).uniform(-0.1, 1.2, (60, k))
    boxes = BoxDecomposition.of(P, ref)
    assert boxes.count == 13 ** (k - 1)
    np.testing.assert_allclose(hypervolume_improvement(boxes, Y), _exact_improvement(P, Y, ref), atol=1e-12)


def test_improvement_over_an_empty_front_is_the_box_to_the_reference():
    boxes = BoxDecomposition.of(np.zeros((0, 2)), np.array([1.0, 2.0]))
    np.testing.assert_allclose(hypervolume_improvement(boxes, np.array([[0.5, 0.5], [2.0, 0.0]])), [0.75, 0.0])


@pytest.mark.parametrize("k", [2, 3])
def test_expectation_matches_monte_carlo(k):
    P, ref = _front(k, 8, 20 + k), np.full(k, 1.1)
    rng = np.random.default_rng(30 + k)
    boxes = BoxDecomposition.of(P, ref)
    for _ in range(3):
        mean, sd = rng.uniform(0.3, 0.9, k), rng.uniform(0.05, 0.3, k)
        samples = _exact_improvement(P, mean + sd * rng.standard_normal((20000, k)), ref)
        expected = expected_improvement(boxes, mean[None, :], sd[None, :])[0]
        assert abs(expected - samples.mean()) < 4.0 * samples.std() / np.sqrt(samples.size) + 1e-12


def test_blocks_of_candidates_agree_with_one_at_a_time():
    P, ref = _front(3, 10, 5), np.full(3, 1.1)
    rng = np.random.default_rng(6)
    mean, sd = rng.uniform(0.2, 1.0, (600, 3)), rng.uniform(0.01, 0.3, (600, 3))
    boxes = BoxDecomposition.of(P, ref)
    together = expected_improvement(boxes, mean, sd)
    alone = np.array([expected_improvement(boxes, mean[i:i + 1], sd[i:i + 1])[0] for i in range(0, 600, 97)])
    np.testing.assert_allclose(together[::97], alone, rtol=1e-12)
