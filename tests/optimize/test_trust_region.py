"""Trust-region steps on a corrected model: known minima, the budget, and the best simulation kept."""

import warnings

import numpy as np

from mechopt.optimize.sparse.trust_region import residual_model, trust_region_steps

BOX = np.array([[0.0, 10.0], [-5.0, 5.0], [100.0, 300.0]])
X_TRUE = np.array([3.0, 1.0, 220.0])
SCALE = BOX[:, 1] - BOX[:, 0]


def truth(x: np.ndarray) -> float:
    z = (np.asarray(x, dtype=float) - X_TRUE) / SCALE
    return float(1.0 + 4.0 * z[0] ** 2 + 9.0 * z[1] ** 2 + z[2] ** 2 + 3.0 * z[0] * z[1])


def biased_model(X: np.ndarray) -> np.ndarray:
    """A model of the right shape whose minimum is a fifth of the box away (a coarse line model)."""
    z = (np.atleast_2d(X) - X_TRUE - 0.2 * SCALE) / SCALE
    return 1.3 + 4.0 * z[:, 0] ** 2 + 9.0 * z[:, 1] ** 2 + z[:, 2] ** 2 + 3.0 * z[:, 0] * z[:, 1]


def everywhere(X: np.ndarray) -> np.ndarray:
    return np.ones(len(np.atleast_2d(X)), dtype=bool)


def start_samples(seed: int, n: int = 12) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    X = BOX[:, 0] + rng.random((n, 3)) * SCALE
    return X, np.array([truth(x) for x in X])


def test_steps_reach_the_minimum_a_biased_model_misses():
    X, q = start_samples(0)
    calls = []

    def simulate(x):
        calls.append(np.array(x))
        return truth(x)

    res = trust_region_steps(biased_model, simulate, everywhere, BOX, X, q, budget=25, seed=0)
    assert len(calls) == res.n_steps <= 25
    # The model alone points a fifth of the box away (truth there: 1 + 0.04 * 14 + ...); the steps find the bottom.
    assert res.value < 1.0 + 1e-3
    np.testing.assert_allclose((res.x - X_TRUE) / SCALE, 0.0, atol=0.03)
    # The returned design is a simulated one, the best of all.
    assert res.value == min(q.min(), min(truth(c) for c in calls))


def test_budget_is_never_exceeded_and_infeasible_designs_never_simulated():
    X, q = start_samples(1)

    def half_space(Xc):
        return np.atleast_2d(Xc)[:, 0] <= 2.0  # the minimum (x0 = 3) lies outside: the steps end on the boundary

    def simulate(x):
        assert half_space(np.asarray(x)[None, :])[0]
        return truth(x)

    inside = half_space(X)
    for budget in (0, 1, 5):
        res = trust_region_steps(biased_model, simulate, half_space, BOX, X, q, budget=budget, seed=2)
        assert res.n_steps <= budget
        assert res.value <= q[inside].min()
    res = trust_region_steps(biased_model, simulate, half_space, BOX, X, q, budget=30, seed=2)
    assert res.x[0] <= 2.0 and res.x[0] > 1.9


def test_failed_simulations_shrink_the_region_and_are_not_kept():
    X, q = start_samples(2)

    def simulate(x):
        return float("nan") if x[1] > 2.0 else truth(x)

    res = trust_region_steps(biased_model, simulate, everywhere, BOX, X, q, budget=20, seed=3)
    assert np.isfinite(res.value) and res.x[1] <= 2.0


def test_designs_in_one_plane_get_the_constant_tail_quietly_and_are_interpolated():
    # Five designs in the plane x3 = 0.5 of the unit cube: a linear tail in 3-D is singular there.
    U = np.array([[0.0, 0.0, 0.5], [1.0, 0.0, 0.5], [0.0, 1.0, 0.5], [1.0, 1.0, 0.5], [0.5, 0.5, 0.5]])
    residual = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = residual_model(U, residual, kernel="cubic")
    np.testing.assert_allclose(model(U), residual, atol=1e-6)
