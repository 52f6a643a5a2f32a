"""Closed-form four-bar kinematics against finite differences and loop closure; the links' axial forces against an
independent Newton-Euler solve of the rigid links (accelerations by finite differences)."""

import numpy as np
import pytest

from mechopt.errors import InfeasibleDesignError
from mechopt.sim.flexible_four_bar import FlexibleFourBar
from mechopt.sim.flexible_four_bar.kinematics import (
    crank_rocker_margins,
    require_crank_rocker,
    rigid_motion,
    transmission_angles,
)
from mechopt.sim.flexible_four_bar.loads import drive_table

LENGTHS = [(0.285, 0.100, 0.250, 0.250), (0.2231, 0.1199, 0.2997, 0.2981), (0.2047, 0.0816, 0.2982, 0.2571)]


@pytest.mark.parametrize("lengths", LENGTHS)
def test_loop_closes_and_derivatives_match_finite_differences(lengths):
    l1, l2, l3, l4 = lengths
    t = np.linspace(0.0, 0.48, 97)
    h = 1e-5
    m, mp, mm = (rigid_motion(lengths, 26.18, t + d) for d in (0.0, h, -h))
    e3 = np.stack([np.cos(m.theta3), np.sin(m.theta3)], axis=1)
    np.testing.assert_allclose(m.B + l3 * e3, m.C, atol=1e-14)  # B + l3 e3 = O4 + l4 e4 = C
    np.testing.assert_allclose(np.linalg.norm(m.C - [l1, 0.0], axis=1), l4, atol=1e-14)
    assert m.C[0, 1] > 0.0  # branch +1: C above the frame at θ2 = 0
    # central differences: error ~ h² θ''' ≈ 1e-10 × 1e4, far below the tolerances
    for th, w, a in (("theta3", "omega3", "alpha3"), ("theta4", "omega4", "alpha4")):
        np.testing.assert_allclose((getattr(mp, th) - getattr(mm, th)) / (2 * h), getattr(m, w), atol=1e-5)
        np.testing.assert_allclose((getattr(mp, w) - getattr(mm, w)) / (2 * h), getattr(m, a), atol=2e-3)


def test_crank_rocker_margins_and_transmission_angle():
    m = crank_rocker_margins(np.array([[285.0, 100.0, 250.0, 250.0], [100.0, 150.0, 200.0, 200.0]]))
    np.testing.assert_allclose(m[0], [185.0, 185.0, 115.0])
    assert m[1, 0] < 0 and m[1, 1] < 0  # crank longer than the frame: not a crank-rocker
    mu_min, mu_max = transmission_angles(LENGTHS[0])
    # law of cosines at θ2 = 0 (d = l1 − l2 = 185 mm) and θ2 = π (d = 385 mm)
    assert np.cos(mu_min) == pytest.approx((2 * 0.25**2 - 0.185**2) / (2 * 0.25**2))
    assert np.cos(mu_max) == pytest.approx((2 * 0.25**2 - 0.385**2) / (2 * 0.25**2))
    with pytest.raises(InfeasibleDesignError, match="l3 \\+ l4 > l1 \\+ l2"):
        require_crank_rocker((0.3, 0.2, 0.2, 0.2))


def _newton_euler(p: FlexibleFourBar, t: float, h: float = 1e-5):
    """Pin forces F_B, F_C (on the coupler) and F_O4 (on the follower) from the 6 rigid-body equations."""
    m = rigid_motion(p.lengths, p.omega, np.array([t - h, t, t + h]))
    e3 = np.stack([np.cos(m.theta3), np.sin(m.theta3)], axis=1)
    g3 = m.B + 0.5 * p.l3 * e3
    g4 = 0.5 * (m.C + [p.l1, 0.0])
    a3, a4 = ((g[2] - 2 * g[1] + g[0]) / h**2 for g in (g3, g4))
    alpha3, alpha4 = ((th[2] - 2 * th[1] + th[0]) / h**2 for th in (m.theta3, m.theta4))
    m3, m4 = p.coupler.mass_per_length * p.l3, p.follower.mass_per_length * p.l4

    def cross_row(r):  # r × F = r_x F_y − r_y F_x
        return [-r[1], r[0]]

    rb, rc, ro = m.B[1] - g3[1], m.C[1] - g3[1], np.array([p.l1, 0.0]) - g4[1]
    rc4 = m.C[1] - g4[1]
    A = np.zeros((6, 6))  # unknowns F_B (0:2), F_C (2:4), F_O4 (4:6)
    A[0, [0, 2]] = 1.0
    A[1, [1, 3]] = 1.0
    A[2, 0:2], A[2, 2:4] = cross_row(rb), cross_row(rc)
    A[3, [4]], A[3, [2]] = 1.0, -1.0
    A[4, [5]], A[4, [3]] = 1.0, -1.0
    A[5, 4:6], A[5, 2:4] = cross_row(ro), -np.array(cross_row(rc4))
    b = [m3 * a3[0], m3 * a3[1], m3 * p.l3**2 / 12 * alpha3, m4 * a4[0], m4 * a4[1], m4 * p.l4**2 / 12 * alpha4]
    F = np.linalg.solve(A, b)
    return F[0:2], F[2:4], F[4:6], m.theta3[1], m.theta4[1]


@pytest.mark.parametrize("lengths", LENGTHS)
def test_axial_forces_match_an_independent_newton_euler_solve(lengths):
    p = FlexibleFourBar(*lengths)
    masses = (p.coupler.mass_per_length * p.l3, p.follower.mass_per_length * p.l4)
    for t in (0.0, 0.037, 0.11, 0.2):
        fb, fc, fo, th3, th4 = _newton_euler(p, t)
        e3, e4 = np.array([np.cos(th3), np.sin(th3)]), np.array([np.cos(th4), np.sin(th4)])
        d3 = drive_table(p.lengths, p.omega, 1, masses, np.array([t]), 3)[0]
        d4 = drive_table(p.lengths, p.omega, 1, masses, np.array([t]), 4)[0]
        scale = np.abs([*fb, *fc, *fo]).max()
        # tension at each end: −F_B·e3 at B, F_C·e3 at C; −F_O4·e4 at O4, −F_C·e4 at C (finite differences ~1e-5)
        assert d3[0] == pytest.approx(-fb @ e3, abs=1e-4 * scale)
        assert d3[0] + d3[1] * p.l3 + d3[2] * p.l3**2 == pytest.approx(fc @ e3, abs=1e-4 * scale)
        assert d4[0] == pytest.approx(-fo @ e4, abs=1e-4 * scale)
        assert d4[0] + d4[1] * p.l4 + d4[2] * p.l4**2 == pytest.approx(-fc @ e4, abs=1e-4 * scale)
