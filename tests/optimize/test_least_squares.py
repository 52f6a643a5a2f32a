"""Gauss-Newton runs and multi-level single linkage against known answers (optimize/least_squares)."""

import math

import numpy as np
import pytest

import mechopt
from mechopt.errors import InputError
from mechopt.optimize.least_squares import choose_starts, critical_distance, gauss_newton
from mechopt.optimize.least_squares.step import gauss_newton_step

T = np.linspace(0.0, 1.0, 12)


def _exponential(U: np.ndarray) -> tuple[np.ndarray, list]:
    """Residuals of a sum of two exponentials, a member of the model class: a = 0.3, b = 0.7 reproduce the data
    exactly (unit-cube coordinates are the parameters)."""
    R = [u[0] * np.exp(-2.0 * u[1] * T) + 0.5 * np.exp(-T) - (0.3 * np.exp(-1.4 * T) + 0.5 * np.exp(-T))
         for u in np.atleast_2d(U)]
    return np.array([float(r @ r) for r in R]), R


def test_zero_residual_fit_is_reproduced_to_machine_precision():
    u0 = np.array([0.9, 0.1])
    values, R = _exponential(u0[None, :])
    run = gauss_newton(_exponential, u0, R[0], values[0], budget=60, step=1e-6)
    np.testing.assert_allclose(run.u, [0.3, 0.7], atol=1e-9)
    assert run.merit < 1e-20
    assert run.nfev <= 25  # measured 17: quadratic convergence, Broyden updates between fresh Jacobians


def test_a_linearised_constraint_is_respected_and_found_active():
    # min (x - 0.8)² + (y - 0.9)² subject to x + y <= 1: the projection (0.45, 0.55).
    def evaluate(U):
        R = [np.array([u[0] - 0.8, u[1] - 0.9]) for u in np.atleast_2d(U)]
        return np.array([r @ r for r in R]), R

    def margins(U):
        return (1.0 - U[:, 0] - U[:, 1])[:, None]

    u0 = np.array([0.1, 0.1])
    v, R = evaluate(u0[None, :])
    run = gauss_newton(evaluate, u0, R[0], v[0], budget=30, step=1e-7, margins=margins,
                       allowed=lambda U: margins(U)[:, 0] >= 0)
    np.testing.assert_allclose(run.u, [0.45, 0.55], atol=1e-7)


def test_step_stays_in_the_trust_box_and_the_unit_cube():
    J = np.eye(3)
    r = np.array([-5.0, 5.0, 0.01])
    p = gauss_newton_step(J, r, np.array([0.95, 0.5, 0.5]), radius=0.2)
    np.testing.assert_allclose(p, [0.05, -0.2, -0.01])


def test_failed_simulations_shrink_the_step_and_the_run_goes_on():
    # The simulator fails where u0 > 0.5; the minimum (0.45, 0.3) is just inside.
    def evaluate(U):
        R = [None if u[0] > 0.5 else np.array([u[0] - 0.45, u[1] - 0.3]) for u in np.atleast_2d(U)]
        return np.array([np.nan if r is None else r @ r for r in R]), R

    u0 = np.array([0.05, 0.9])
    v, R = evaluate(u0[None, :])
    run = gauss_newton(evaluate, u0, R[0], v[0], budget=60, step=1e-7, radius=0.5)
    np.testing.assert_allclose(run.u, [0.45, 0.3], atol=1e-8)


def test_critical_distance_is_mlsl_formula_and_shrinks():
    # d = 2: r = sqrt(σ log N / (π N)) since Γ(2) = 1
    assert critical_distance(100, 2) == pytest.approx(math.sqrt(4.0 * math.log(100) / 100 / math.pi))
    assert critical_distance(1000, 5) < critical_distance(100, 5)


def test_starts_are_local_minima_of_the_sample_away_from_explored_designs():
    U = np.array([[0.1, 0.1], [0.12, 0.1], [0.9, 0.9], [0.5, 0.5]])
    values = np.array([1.0, 0.5, 0.7, np.nan])
    starts = choose_starts(U, values, explored=np.zeros((0, 2)), radius=0.1, limit=5)
    assert starts.tolist() == [1, 2]  # 0 has a better neighbour (1); 3 failed
    starts = choose_starts(U, values, explored=np.array([[0.88, 0.9]]), radius=0.1, limit=5)
    assert starts.tolist() == [1]


class _TwoBasins(mechopt.DesignProblem):
    """Residuals with a zero at (1.5, -1) and a local minimum (f ≈ 4.6) near (-1.4, -1)."""

    name = "two-basins-ls"
    variables = (mechopt.Variable("a", -2.0, 2.0), mechopt.Variable("b", -2.0, 2.0))
    outputs = ("f",)
    objective = "f"
    residuals = "r"

    def evaluate(self, x):
        a, b = x
        r = [(a - 1.5) * (a + 1.5), b + 1.0, min(a, 0.0) ** 2]
        return {"f": float(np.dot(r, r)), "r": [float(v) for v in r]}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_default_method_finds_the_zero_residual_basin(seed):
    res = mechopt.minimize(_TwoBasins(), budget=80, method="auto", seed=seed)
    assert res.plan == "least-squares"
    assert res.fun < 1e-16
    np.testing.assert_allclose(res.x, [1.5, -1.0], atol=1e-7)


def test_residuals_that_are_not_a_flat_finite_list_are_a_one_line_error():
    class Bad(_TwoBasins):
        name = "bad-ls"

        def evaluate(self, x):
            return {"f": 1.0, "r": [[1.0, 2.0]]}

    with pytest.raises(InputError, match="flat list of finite numbers"):
        Bad().residual_vector(Bad().evaluate(np.zeros(2)))
    with pytest.raises(InputError, match="declares no residuals"):
        mechopt.DesignProblem().residual_vector({})


def test_polish_in_the_variables_units_counts_distinct_designs():
    from mechopt.optimize.least_squares import least_squares_polish

    asked = []

    def residuals(X):
        asked.extend(map(tuple, X))
        R = [np.array([x[0] - 30.0, 2.0 * (x[1] - 0.004)]) for x in X]
        return np.array([r @ r for r in R]), R

    bounds = np.array([[0.0, 100.0], [0.0, 0.01]])  # mm and m: the unit cube makes the step scale-free
    x, run = least_squares_polish(residuals, bounds, np.array([90.0, 0.009]), budget=12, fd_step=1e-6)
    np.testing.assert_allclose(x, [30.0, 0.004], rtol=1e-9)
    assert len(asked) == len(set(asked)) <= 12
    x, run = least_squares_polish(residuals, bounds, np.array([90.0, 0.009]), budget=2, fd_step=1e-6)
    assert run.nfev <= 1 and x[0] == 90.0  # no room for a Jacobian: the start is kept
