"""Kinematics against hand-computed cases, an independent numerical derivative and pymunk's joint positions."""

import numpy as np
import pytest

from mechopt.errors import InputError
from mechopt.sim.four_bar.kinematics import check_design, crank_angle, joint_positions, rocker_angle
from mechopt.sim.four_bar.pymunk_engine import simulate_pymunk


def test_parallelogram_by_hand():
    # O-A-B-C with C = (100, 0), |OA| = |BC| = 30, |AB| = 100: one assembly is the parallelogram, θ = ψ exactly.
    psi = np.linspace(0.2, 1.4, 7)
    branches = {}
    for branch in (-1, 1):
        theta, d1, d2 = crank_angle((30, 100, 30), (100, 0), psi, branch)
        branches[branch] = (theta, d1, d2)
    theta, d1, d2 = next(v for v in branches.values() if np.allclose(v[0], psi, atol=1e-12))
    np.testing.assert_allclose(d1, 1.0, atol=1e-12)
    np.testing.assert_allclose(d2, 0.0, atol=1e-12)


def test_right_angle_by_hand():
    # C = (0, 100), |BC| = 100, ψ = 0 puts B at (100, 100); with |OA| = 100 and |AB| = 100 the pin A is at (100, 0)
    # or (0, 100): θ = 0 or 90°.
    thetas = sorted(float(crank_angle((100, 100, 100), (0, 100), 0.0, b)[0][0]) for b in (-1, 1))
    np.testing.assert_allclose(thetas, [0.0, np.pi / 2], atol=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_loop_closes_and_derivatives_match_independent_differences(seed):
    rng = np.random.default_rng(seed)
    design = np.array([40.0, 80.0, 270.0]) + rng.uniform(-5, 5, 3)
    pivot = (-235.0 + rng.uniform(-5, 5), 11.0 + rng.uniform(-5, 5))
    psi = np.linspace(0.12, 0.28, 9)
    theta, d1, d2 = crank_angle(design, pivot, psi)
    pos = joint_positions(design, pivot, psi)
    np.testing.assert_allclose(np.linalg.norm(pos["B"] - pos["A"], axis=-1), design[1], rtol=1e-12)
    h = 1e-4
    th = [np.unwrap(crank_angle(design, pivot, psi + k * h)[0]) for k in (-2, -1, 1, 2)]
    fd1 = (th[0] - 8 * th[1] + 8 * th[2] - th[3]) / (12 * h)  # fourth-order central differences
    fd2 = (-th[0] + 16 * th[1] - 30 * np.unwrap(theta) + 16 * th[2] - th[3]) / (12 * h * h)
    np.testing.assert_allclose(d1, fd1, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(d2, fd2, rtol=1e-5, atol=1e-6)


def test_forward_and_inverse_kinematics_agree():
    design, pivot = (53.0, 65.0, 282.0), (-235.3, 11.2)
    theta = np.radians(np.linspace(-26, 30, 15))
    psi, dpsi = rocker_angle(design, pivot, theta, branch=1)
    back, dtheta, _ = crank_angle(design, pivot, psi, branch=-1)
    np.testing.assert_allclose(np.angle(np.exp(1j * (back - theta))), 0.0, atol=1e-11)
    np.testing.assert_allclose(dpsi * dtheta, 1.0, rtol=1e-10)


def test_pymunk_joint_positions_follow_the_kinematics(ventilator, mechanism):
    result = simulate_pymunk(ventilator.design("original"), mechanism, n_steps=400, extrapolate=False)
    psi_ref, _, _ = mechanism.motion(result.t)
    theta_ref = np.unwrap(crank_angle(result.design, mechanism.pivot_c, psi_ref)[0])
    # The crank is driven onto θ(t); the rocker, moved by pymunk through the coupler, must land on ψ(t).
    np.testing.assert_allclose(result.theta, theta_ref, atol=1e-7)
    np.testing.assert_allclose(result.psi, psi_ref, atol=2e-4)


@pytest.mark.parametrize("bad", [(0, 65, 282), (53, -1, 282), (53, 65, float("nan")), (53, 65)])
def test_bad_lengths_are_one_line_errors(bad):
    with pytest.raises(InputError) as info:
        check_design(bad)
    assert "\n" not in str(info.value)
