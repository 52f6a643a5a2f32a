"""Analytic inverse dynamics against an independent energy balance, and the ventilator's original design."""

import dataclasses

import numpy as np
import pytest

from mechopt.sim.four_bar.analytic import analytic_batch, simulate_analytic, torque_curve
from mechopt.sim.four_bar.kinematics import crank_angle, joint_positions


def _energy(design_mm, mech, t):
    """Kinetic energy (J) from joint positions alone: velocities by 4th-order central differences in time."""
    h = 1e-6

    def positions(tt):
        psi, _, _ = mech.motion(tt)
        pos = joint_positions(design_mm, mech.pivot_c, psi)
        theta = np.unwrap(crank_angle(design_mm, mech.pivot_c, psi)[0])
        a, b = pos["A"] * 1e-3, pos["B"] * 1e-3
        phi = np.unwrap(np.arctan2(b[:, 1] - a[:, 1], b[:, 0] - a[:, 0]))
        return theta, psi, (a + b) / 2, phi

    samples = [positions(t + k * h) for k in (-2, -1, 1, 2)]

    def rate(idx):
        f = [s[idx] for s in samples]
        return (f[0] - 8 * f[1] + 8 * f[2] - f[3]) / (12 * h)

    theta_dot, psi_dot, v_g, phi_dot = rate(0), rate(1), rate(2), rate(3)
    ab = design_mm[1] * 1e-3
    m_c = mech.coupler_mass
    return 0.5 * (mech.j0 * theta_dot**2 + mech.i_r * psi_dot**2 + m_c * np.sum(v_g**2, axis=1)
                  + m_c * ab**2 / 12 * phi_dot**2)


@pytest.mark.parametrize("coupler_mass", [0.0, 0.35])
def test_power_balance(mechanism, coupler_mass):
    # τ θ̇ = dE/dt + M_r ψ̇, with E computed from positions only: independent of the Lagrange form of the engine.
    mech = dataclasses.replace(mechanism, coupler_mass=coupler_mass)
    design = np.array([38.0, 78.0, 268.0])
    t = np.linspace(0.01, 0.39, 77)
    t = t[np.abs(t - 0.2) > 0.01]  # θ̇ = 0 at the stroke's turn: both sides vanish there
    h = 1e-5
    energy = [_energy(design, mech, t + k * h) for k in (-2, -1, 1, 2)]
    de_dt = (energy[0] - 8 * energy[1] + 8 * energy[2] - energy[3]) / (12 * h)
    psi, psi_dot, _ = mech.motion(t)
    _, d1, _ = crank_angle(design, mech.pivot_c, psi)
    tau = torque_curve(design, mech, t)
    lhs = tau * d1 * psi_dot
    rhs = de_dt + mech.load(psi) * psi_dot
    np.testing.assert_allclose(lhs, rhs, rtol=0, atol=1e-6 * np.max(np.abs(lhs)))


def test_stroke_ends_are_exact(mechanism):
    # At rest (ψ̇ = ψ̈ = 0 for the quintic law) the torque is the static one, M_r / θ' — no 0/0.
    design = np.array([53.0, 65.0, 282.0])
    t = np.array([0.0, 0.2, 0.4])
    psi, _, _ = mechanism.motion(t)
    _, d1, _ = crank_angle(design, mechanism.pivot_c, psi)
    np.testing.assert_allclose(torque_curve(design, mechanism, t), mechanism.load(psi) / d1, rtol=1e-12)


def test_original_design_figures(ventilator, mechanism):
    result = simulate_analytic(ventilator.design("original"), mechanism)
    assert result.t_rms == pytest.approx(4.78, abs=0.01)
    assert result.t_max == pytest.approx(8.06, abs=0.01)


def test_batch_equals_single(ventilator, mechanism):
    rng = np.random.default_rng(3)
    designs = rng.uniform(ventilator.problem.bounds[:, 0], ventilator.problem.bounds[:, 1], size=(300, 3))
    t_rms, t_max = analytic_batch(designs, mechanism)
    ok = np.flatnonzero(np.isfinite(t_rms))
    assert ok.size > 50
    for i in ok[:5]:
        single = simulate_analytic(designs[i], mechanism)
        assert t_rms[i] == pytest.approx(single.t_rms, rel=1e-12)
        assert t_max[i] == pytest.approx(single.t_max, rel=1e-12)


def test_quadrature_converged(ventilator, mechanism):
    # The default time grid resolves T_RMS far below the 0.5 % the engines are compared at.
    design = ventilator.design("paper_global_optimum")
    coarse = simulate_analytic(design, mechanism).t_rms
    fine = simulate_analytic(design, mechanism, n_intervals=8000).t_rms
    assert coarse == pytest.approx(fine, rel=1e-5)
