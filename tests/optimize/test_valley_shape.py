"""The default method learns a valley's orientation and scale: on a rotated quadratic of condition 10^6 its
quadratic trust-region steps (mechopt.optimize.auto.quadratic_steps) reach the minimum at a small budget, where
the Gaussian process with one length-scale per axis alone stays far above it."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import special_ortho_group

from mechopt.optimize.auto import auto_search
from mechopt.optimize.auto import quadratic_steps as steps_module


def _rotated_ellipsoid(d: int, seed: int):
    rng = np.random.default_rng(seed)
    Q = special_ortho_group.rvs(d, random_state=rng)
    w = 10.0 ** (6.0 * np.arange(d) / (d - 1))
    shift = rng.uniform(-3.0, 3.0, d)
    return lambda X: np.sum(w * ((np.atleast_2d(X) - shift) @ Q.T) ** 2, axis=1)


@pytest.mark.parametrize("seed", [0, 1])
def test_rotated_ill_conditioned_quadratic_is_solved_at_ten_simulations_a_variable(seed, monkeypatch):
    f = _rotated_ellipsoid(3, 11)
    bounds = np.array([[-5.0, 5.0]] * 3)
    learned = auto_search(f, bounds, 30, seed=seed).fun
    # The same run without the quadratic steps: the axis-aligned GP alone.
    monkeypatch.setattr(steps_module.QuadraticSteps, "propose", lambda self, U, values, allowed: U[:0])
    axis_aligned = auto_search(f, bounds, 30, seed=seed).fun
    assert learned < 1e-6
    assert axis_aligned > 1.0


def test_quadratic_steps_wait_where_no_quadratic_describes_the_designs():
    rng = np.random.default_rng(0)
    U = rng.random((40, 2))
    steps = steps_module.QuadraticSteps(2)
    assert steps.propose(U, rng.random(40), lambda C: np.ones(len(C), dtype=bool)).shape == (0, 2)


def test_quadratic_steps_back_off_while_they_miss():
    # A bowl the model describes, but every step's simulation comes out high (and is kept out of the designs, which
    # would otherwise stop describing a bowl): the waits between steps double.
    rng = np.random.default_rng(0)
    U = rng.random((40, 2))
    values = np.sum((U - 0.5) ** 2, axis=1)
    steps = steps_module.QuadraticSteps(2)
    taken = 0
    for _ in range(60):
        x = steps.propose(U, values, lambda C: np.ones(len(C), dtype=bool))
        if x.shape[0]:
            taken += 1
            steps.learn(x, np.array([10.0]))
    assert 4 <= taken <= 6  # steps 1, 3, 7, 15, 31: about log2 of the steps
    assert steps.radius < steps_module.START_RADIUS
