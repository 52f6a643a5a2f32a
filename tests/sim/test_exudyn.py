"""The Exudyn multibody engine against the analytic inverse dynamics, on ordinary and boundary designs."""

from __future__ import annotations

import dataclasses
import functools
import multiprocessing
import os
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest
from scipy.optimize import brentq

from mechopt.errors import InfeasibleDesignError, InputError, MechoptError
from mechopt.sim.four_bar.analytic import simulate_analytic, torque_curve
from mechopt.sim.four_bar.exudyn_engine import simulate_exudyn
from mechopt.sim.four_bar.feasibility import check_feasibility
from mechopt.sim.four_bar.kinematics import crank_angle
from mechopt.sim.four_bar.simulate import ENGINES, simulate

pytest.importorskip("exudyn")

#: Relative T_RMS agreement required with the analytic engine (the issue's 0.1 %).
RTOL = 1e-3


@pytest.fixture(scope="module")
def cloud(ventilator, mechanism):
    """5000 seeded designs of the study's box and their feasibility report."""
    box = np.array([(v.lower, v.upper) for v in ventilator.problem.variables])
    designs = np.random.default_rng(2024).uniform(box[:, 0], box[:, 1], size=(5000, 3))
    return designs, check_feasibility(designs, mechanism)


def _at_toggle_margin(mechanism, cloud, n):
    """Feasible designs with a toggle margin in [0, 1e-6]° (on the segment from a feasible design to a movable one
    that violates the toggle margin)."""
    designs, report = cloud
    inside = designs[report.feasible]
    outside = designs[report.movable & (report.toggle_deg < 0)]
    found = []
    for a, b in zip(inside, outside, strict=False):
        def toggle(s, a=a, b=b):
            return check_feasibility(a + s * (b - a), mechanism).toggle_deg[0]

        s = brentq(toggle, 0.0, 1.0, xtol=1e-13)
        x = a + s * (b - a)
        while toggle(s) < 0:
            s -= 1e-12
            x = a + s * (b - a)
        r = check_feasibility(x, mechanism)
        if r.feasible[0] and r.toggle_deg[0] <= 1e-6:
            found.append(x)
        if len(found) == n:
            return found
    raise AssertionError("too few designs at the toggle margin")


def _relative_error(design, mechanism):
    sim = simulate_exudyn(design, mechanism)
    ref = simulate_analytic(design, mechanism, n_intervals=4000)
    return sim, ref, sim.t_rms / ref.t_rms - 1.0


def test_original_design(ventilator, mechanism):
    sim = simulate_exudyn(ventilator.design("original"), mechanism)
    assert sim.engine == "exudyn" and sim.feasible and sim.dt == pytest.approx(0.002)
    # The figures of the analytic and pymunk engines (4.78 and 8.06 N·m; the paper's CAD: 7.91 and 13.26).
    assert sim.t_rms == pytest.approx(4.778, abs=0.002)
    assert sim.t_max == pytest.approx(8.064, abs=0.002)


def test_random_feasible_designs(mechanism, cloud):
    designs, report = cloud
    for d in designs[report.feasible][:4]:
        _, _, err = _relative_error(d, mechanism)
        assert abs(err) < RTOL, (d, err)


def test_feasible_designs_within_1mm_of_assembly(mechanism, cloud):
    # Feasible and less than 1 mm from losing assembly somewhere in the stroke: the poorest transmission a
    # feasible design has (the toggle margin keeps feasible designs ~0.8 mm away at best).
    designs, report = cloud
    near = designs[report.feasible & (report.assembly_stroke_mm < 1.0)]
    assert near.shape[0] >= 2
    for d in near[:3]:
        _, _, err = _relative_error(d, mechanism)
        assert abs(err) < RTOL, (d, err)


def test_designs_at_the_toggle_margin(mechanism, cloud):
    for d in _at_toggle_margin(mechanism, cloud, 3):
        _, _, err = _relative_error(d, mechanism)
        assert abs(err) < RTOL, (d, err)


@pytest.mark.parametrize("distance_mm", [0.05, 0.5])
def test_movable_designs_at_the_assembly_boundary(ventilator, mechanism, distance_mm):
    # Beyond the toggle margin but still movable (the sampler visits these): 0.05 mm from the boundary.
    base = ventilator.design("paper_global_optimum")
    ab = brentq(lambda ab: check_feasibility((base[0], ab, base[2]), mechanism).assembly_stroke_mm[0] - distance_mm,
                base[1], base[1] + 40.0, xtol=1e-10)
    design = np.array([base[0], ab, base[2]])
    sim, _, err = _relative_error(design, mechanism)
    assert not sim.feasible and abs(err) < RTOL, err


def test_signed_torque_curve(ventilator, mechanism):
    design = ventilator.design("paper_local_optimum")
    sim = simulate_exudyn(design, mechanism)
    reference = torque_curve(design, mechanism, sim.t)
    # Pointwise, not only in RMS; the sign included (the curve changes sign over the cycle).
    assert np.any(reference < -0.5) and np.any(reference > 0.5)
    assert np.max(np.abs(sim.tau - reference)) < 1e-3 * np.sqrt(np.mean(reference**2))
    # At the start the mechanism rests: τ is the static torque M_r/θ'.
    _, d1, _ = crank_angle(design, mechanism.pivot_c, mechanism.psi_start)
    assert sim.tau[0] == pytest.approx(float(mechanism.load(mechanism.psi_start) / d1[0]), rel=1e-9)
    # The crank and rocker angles of the multibody run are those of the closed-form kinematics.
    np.testing.assert_allclose(sim.psi, mechanism.motion(sim.t)[0], atol=1e-4)


def test_error_is_second_order_in_the_step(ventilator, mechanism):
    design = ventilator.design("original")
    errors = []
    for n in (100, 200):
        sim = simulate_exudyn(design, mechanism, n_steps=n)
        curve = torque_curve(design, mechanism, sim.t)
        errors.append(np.sqrt(np.mean((sim.tau - curve) ** 2)))
    assert 3.0 < errors[0] / errors[1] < 5.0, errors


def test_coupler_with_mass(mechanism):
    heavy = dataclasses.replace(mechanism, coupler_mass=0.35)
    design = np.array([38.0, 78.0, 268.0])
    sim, ref, err = _relative_error(design, heavy)
    assert abs(err) < RTOL, err
    # The coupler's mass matters here, so the test would see it missing.
    light = simulate_analytic(design, mechanism, n_intervals=4000)
    assert abs(ref.t_rms / light.t_rms - 1.0) > 10 * RTOL


def test_infeasible_designs_raise(mechanism, cloud):
    designs, report = cloud
    never = designs[report.assembly_start_mm < 0][0]
    with pytest.raises(InfeasibleDesignError, match="not assemblable at ψ_start"):
        simulate_exudyn(never, mechanism)
    # Assembles where the stroke starts, but the loop opens (or the crank turns back) on the way.
    midway = designs[(report.assembly_start_mm >= 0) & ~report.movable][0]
    with pytest.raises(InfeasibleDesignError):
        simulate_exudyn(midway, mechanism)


def test_bad_input_and_missing_exudyn(ventilator, mechanism, monkeypatch):
    design = ventilator.design("original")
    with pytest.raises(InputError, match="n_steps"):
        simulate_exudyn(design, mechanism, n_steps=5)
    # Too few steps: the drift guard, not a silently wrong torque.
    with pytest.raises(MechoptError, match="drifted off the closed loop"):
        simulate_exudyn(design, mechanism, n_steps=20)
    monkeypatch.setitem(sys.modules, "exudyn", None)  # what `import exudyn` sees when it is not installed
    with pytest.raises(InputError, match="needs the exudyn package") as info:
        simulate(design, mechanism, engine="exudyn")
    assert "\n" not in str(info.value)


def test_writes_no_files(ventilator, mechanism, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    simulate_exudyn(ventilator.design("original"), mechanism, n_steps=60)
    assert os.listdir(tmp_path) == []


def test_process_pool_gives_the_in_process_results(ventilator, mechanism):
    assert "exudyn" in ENGINES
    designs = [ventilator.design(name) for name in ("original", "paper_global_optimum")]
    run = functools.partial(simulate, mechanism=mechanism, engine="exudyn")
    context = multiprocessing.get_context("forkserver" if "forkserver" in multiprocessing.get_all_start_methods()
                                          else "spawn")
    with ProcessPoolExecutor(max_workers=2, mp_context=context) as pool:
        remote = list(pool.map(run, designs))
    for d, r in zip(designs, remote, strict=True):
        local = run(d)
        # Same numbers bit for bit: nothing leaks between runs or processes.
        assert r.t_rms == local.t_rms and r.t_max == local.t_max
        np.testing.assert_array_equal(r.tau, local.tau)
