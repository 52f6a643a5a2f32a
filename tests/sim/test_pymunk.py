"""The pymunk motion simulation against the analytic inverse dynamics."""

import numpy as np
import pytest
from scipy.optimize import brentq

from mechopt.sim.four_bar.analytic import MM, simulate_analytic, torque_curve
from mechopt.sim.four_bar.feasibility import check_feasibility
from mechopt.sim.four_bar.kinematics import crank_angle
from mechopt.sim.four_bar.pymunk_engine import _run, simulate_pymunk


def _boundary_design(mechanism, base, distance_mm):
    """A design ``distance_mm`` inside the assembly boundary at ψ_end, moving |AB| from ``base``."""

    def margin(ab):
        return check_feasibility((base[0], ab, base[2]), mechanism).assembly_stroke_mm[0] - distance_mm

    ab = brentq(margin, base[1], base[1] + 40.0, xtol=1e-10)
    return np.array([base[0], ab, base[2]])


def _random_feasible(ventilator, mechanism, n, seed):
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        d = rng.uniform(ventilator.problem.bounds[:, 0], ventilator.problem.bounds[:, 1])
        if check_feasibility(d, mechanism).feasible[0]:
            out.append(d)
    return out


def test_signed_torque_and_pymunk_impulse(ventilator, mechanism):
    design = ventilator.design("original")
    t = mechanism.motion.time_grid(400)
    psi, _, _ = mechanism.motion(t)
    theta = np.unwrap(crank_angle(design, mechanism.pivot_c, psi)[0])
    tau, _, _, impulse = _run(design * MM, mechanism, theta, psi[0], t[1] - t[0], 20, 40)
    # Magnitude from pymunk's own (unsigned) motor impulse, sign from the stator's reaction.
    np.testing.assert_allclose(np.abs(tau), impulse, rtol=1e-9, atol=1e-9)
    reference = torque_curve(design, mechanism, t)
    strong = np.abs(reference) > 0.2
    assert np.any(reference[strong] < 0) and np.any(reference[strong] > 0)  # the curve changes sign
    np.testing.assert_array_equal(np.sign(tau[strong]), np.sign(reference[strong]))
    # The start pose was held: the very first recorded sample is already the static torque.
    assert tau[0] == pytest.approx(reference[0], rel=2e-2)


def test_twenty_random_designs_and_near_the_boundary(ventilator, mechanism):
    designs = _random_feasible(ventilator, mechanism, 16, seed=11)
    optimum = ventilator.design("paper_global_optimum")
    designs += [_boundary_design(mechanism, optimum, mm) for mm in (0.5, 1.0, 2.0, 3.0)]
    assert len(designs) >= 20
    for d in designs:
        sim = simulate_pymunk(d, mechanism)
        ref = simulate_analytic(d, mechanism, n_intervals=4000)
        assert sim.t_rms == pytest.approx(ref.t_rms, rel=5e-3), d
        curve = torque_curve(d, mechanism, sim.t)
        assert np.sqrt(np.mean((sim.tau - curve) ** 2)) <= 1e-2 * np.sqrt(np.mean(curve**2)), d


@pytest.mark.parametrize("where", ["middle", "boundary"])
def test_error_is_smooth_along_a_line(ventilator, mechanism, where):
    # 50 designs 0.2 mm apart: the relative error may not jump (the surrogate fits exponentials to these values).
    if where == "middle":
        direction = np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)
        designs = [ventilator.design("original") - 0.2 * k * direction for k in range(50)]
    else:
        # The line ends 0.5 mm from the assembly boundary at ψ_end, where the transmission is poorest.
        end = _boundary_design(mechanism, ventilator.design("paper_global_optimum"), 0.5)
        designs = [end - 0.2 * (49 - k) * np.array([0.0, 1.0, 0.0]) for k in range(50)]
    errors = []
    for d in designs:
        sim = simulate_pymunk(d, mechanism)
        ref = simulate_analytic(d, mechanism, n_intervals=4000)
        errors.append(sim.t_rms / ref.t_rms - 1.0)
    steps = np.abs(np.diff(errors))
    assert steps.max() < 1e-4, steps.max()
