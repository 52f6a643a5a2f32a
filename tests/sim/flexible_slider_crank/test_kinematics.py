"""Closed-form rigid slider-crank kinematics against numerical differentiation and the rod-frame identities."""

import numpy as np

from mechopt.sim.flexible_slider_crank.kinematics import rigid_motion


def test_derivatives_match_finite_differences():
    r, l, w = 0.05, 0.35, 26.19
    t = np.linspace(0.0, 0.48, 97)
    h = 1e-5
    m, mp, mm = rigid_motion(r, l, w, t), rigid_motion(r, l, w, t + h), rigid_motion(r, l, w, t - h)
    # central differences: error ~ h² x''' ≈ 1e-10 × 1e3, far below the tolerances
    np.testing.assert_allclose((mp.x - mm.x) / (2 * h), m.v, atol=1e-6)
    np.testing.assert_allclose((mp.v - mm.v) / (2 * h), m.acc, atol=1e-4)
    np.testing.assert_allclose((mp.phi - mm.phi) / (2 * h), m.phi_d, atol=1e-7)
    np.testing.assert_allclose((mp.phi_d - mm.phi_d) / (2 * h), m.phi_dd, atol=1e-4)


def test_slider_position_and_rod_frame_accelerations_are_consistent():
    r, l, w = 0.065, 0.40, 26.19
    t = np.linspace(0.0, 0.48, 121)
    m = rigid_motion(r, l, w, t)
    # B = A + l e closes the loop on the x axis
    ax_, ay_ = r * np.cos(m.theta), r * np.sin(m.theta)
    np.testing.assert_allclose(ax_ + l * np.cos(m.phi), m.x, atol=1e-14)
    np.testing.assert_allclose(ay_ + l * np.sin(m.phi), 0.0, atol=1e-14)
    # B's rigid acceleration from the rod frame: a_A + φ̈ l n − φ̇² l e must be (acc, 0) in the global frame
    e = np.stack([np.cos(m.phi), np.sin(m.phi)])
    n = np.stack([-np.sin(m.phi), np.cos(m.phi)])
    a_par = m.aA_par - m.phi_d**2 * l
    a_perp = m.aA_perp + m.phi_dd * l
    a_b = a_par * e + a_perp * n
    np.testing.assert_allclose(a_b[0], m.acc, atol=1e-10)
    np.testing.assert_allclose(a_b[1], 0.0, atol=1e-10)
