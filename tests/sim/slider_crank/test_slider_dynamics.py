"""Slider-crank dynamics: the analytic engine against an energy balance, pymunk against the analytic engine."""

import numpy as np
import pytest

from mechopt.errors import InputError
from mechopt.sim.slider_crank.analytic import simulate_analytic, torque_curve
from mechopt.sim.slider_crank.kinematics import joint_positions, slider_position
from mechopt.sim.slider_crank.mechanism import SliderCrank
from mechopt.sim.slider_crank.motion import CrankMotion
from mechopt.sim.slider_crank.pymunk_engine import simulate_pymunk


def _mechanism(**kw):
    base = dict(motion=CrankMotion.from_rpm(90.0, 20.0, 0.3), j0=0.02, rod_mass=0.6, rod_com=0.4, slider_mass=1.5,
                spring_k=1.5, spring_free_mm=120.0, force=-30.0, gravity=9.81)
    base.update(kw)
    return SliderCrank(**base)


def _random_designs(seed, n):
    rng = np.random.default_rng(seed)
    r = rng.uniform(30, 80, n)
    h = rng.uniform(-0.8, 0.8, n) * r
    l = (r + np.abs(h)) * rng.uniform(1.3, 3.0, n)
    return np.column_stack([r, l, h])


def test_analytic_torque_is_the_energy_balance():
    """τ θ̇ = d(E_kin + E_spring + E_gravity)/dt − F ẋ, the energies from joint positions differentiated numerically."""
    mech = _mechanism()
    for d in _random_designs(5, 4):
        t = mech.motion.time_grid(20000)
        theta, thd, _ = mech.motion(t)
        pos = {k: v * 1e-3 for k, v in joint_positions(d, theta).items()}
        g = pos["A"] + mech.rod_com * (pos["B"] - pos["A"])
        rod = pos["B"] - pos["A"]
        phi = np.unwrap(np.arctan2(rod[:, 1], rod[:, 0]))
        vg, vb, om = np.gradient(g, t, axis=0), np.gradient(pos["B"][:, 0], t), np.gradient(phi, t)
        i3 = mech.rod_inertia_si(d[1] * 1e-3)
        e_kin = 0.5 * (mech.j0 * thd**2 + mech.rod_mass * np.sum(vg**2, axis=1) + i3 * om**2 + mech.slider_mass * vb**2)
        x = pos["B"][:, 0]
        e_pot = 0.5 * mech.spring_k * 1e3 * (x - mech.spring_free_mm * 1e-3) ** 2
        e_pot += mech.rod_mass * mech.gravity * g[:, 1]
        power = np.gradient(e_kin + e_pot, t) - mech.force * vb
        tau = torque_curve(d, mech, t)
        inner = slice(5, -5)
        np.testing.assert_allclose(tau[inner] * thd[inner], power[inner], atol=2e-4 * np.max(np.abs(power)))


def test_pymunk_matches_analytic_on_seeded_random_designs():
    mech = _mechanism()
    for d in _random_designs(7, 6):
        sim = simulate_pymunk(d, mech)
        ref = simulate_analytic(d, mech, n_intervals=4000)
        assert sim.t_rms == pytest.approx(ref.t_rms, rel=5e-3), d
        curve = torque_curve(d, mech, sim.t)
        assert np.sqrt(np.mean((sim.tau - curve) ** 2)) <= 1e-2 * np.sqrt(np.mean(curve**2)), d
        # Signed torque: it changes sign over the revolution and pymunk agrees where it is not small.
        strong = np.abs(curve) > 0.2 * np.max(np.abs(curve))
        assert np.any(curve[strong] < 0) and np.any(curve[strong] > 0)
        np.testing.assert_array_equal(np.sign(sim.tau[strong]), np.sign(curve[strong]))
        # The crank lands on the prescribed angle; the slider sits where the kinematics put it, up to the joint
        # drift of pymunk's velocity-level solver (< 0.2 % of the rod).
        np.testing.assert_allclose(sim.theta, mech.motion(sim.t)[0], atol=1e-9)
        np.testing.assert_allclose(sim.x, slider_position(d, sim.theta)[0], atol=2e-3 * d[1])


def test_pymunk_massless_rod_and_constant_speed():
    mech = _mechanism(rod_mass=0.0, motion=CrankMotion.from_rpm(60.0), gravity=0.0)
    d = np.array([40.0, 130.0, 15.0])
    sim = simulate_pymunk(d, mech)
    ref = simulate_analytic(d, mech, n_intervals=4000)
    assert sim.t_rms == pytest.approx(ref.t_rms, rel=5e-3)


def test_pymunk_error_shrinks_with_the_step():
    mech = _mechanism()
    d = np.array([60.0, 150.0, 30.0])
    ref = simulate_analytic(d, mech, n_intervals=4000).t_rms
    errors = [abs(simulate_pymunk(d, mech, n_steps=n, extrapolate=False).t_rms - ref) for n in (360, 1440)]
    assert errors[1] < 0.5 * errors[0]


def test_pymunk_needs_a_slider_mass():
    with pytest.raises(InputError, match="slider_mass"):
        simulate_pymunk((40.0, 130.0, 0.0), _mechanism(slider_mass=0.0))
