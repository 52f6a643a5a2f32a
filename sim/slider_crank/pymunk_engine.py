"""pymunk rigid-body motion simulation of a slider-crank, checked against :mod:`.analytic`.

The space (SI units, gravity −g along y, ``damping = 1``, no sleeping, no shapes) holds

* the crank (J0 about O, pinned at O on its centre of mass), driven by a ``SimpleMotor`` against a *stator* body;
  the motor's rate is set inside every step (``pre_solve``, after pymunk has moved the bodies) to
  (θ(t_{k+1}) − θ_k)/dt: position feedback that lands the crank on the prescribed angle at every step;
* the rod, a body of mass m_3 and inertia I_3 at its centre of mass, pinned to the crank at A and to the slider at B
  (a distance joint A–B, a two-force member, when the rod is massless);
* the slider, a body on a ``GrooveJoint`` along the line y = h; the spring and the external force act on it through
  its ``velocity_func``, which pymunk calls after moving the bodies, so the spring sees this step's position.

**Signed torque.**  pymunk reports a constraint's impulse unsigned.  The stator is a dynamic body pivoted at O on its
centre of mass, so the only angular impulse it receives is the motor's reaction: τ = −I_s ω_s / dt after each step
(the stator is then reset to rest) — a cradle-mounted motor, as in the four-bar engine.

**Start.**  The crank is already turning at t = 0, so the bodies start with the velocities of the prescribed motion
(from the exact kinematics) one lead-in of ``lead_steps`` steps before t = 0, and the solver's warm start has
settled when recording begins.  The recorded torque's error is first order in dt; a second run at twice the step
removes that term (Richardson extrapolation).
"""

from __future__ import annotations

import time

import numpy as np
import pymunk

from mechopt.errors import InputError
from mechopt.sim.slider_crank.analytic import MM, rms_over_cycle
from mechopt.sim.slider_crank.feasibility import COLUMNS, require_assemblable
from mechopt.sim.slider_crank.kinematics import _slider_kernel, check_design
from mechopt.sim.slider_crank.mechanism import SliderCrank
from mechopt.sim.slider_crank.result import SliderCrankResult

#: Moment of inertia of the stator (kg·m²): large, so it barely turns within a step, yet its angular velocity keeps
#: ~13 significant digits of the motor's reaction impulse.
STATOR_MOMENT = 1.0e3
#: Mass of the bodies pinned at their centre of mass (crank, stator), kg: it never accelerates, so adds no torque.
PIN_MASS = 1.0
#: Steps of the prescribed motion run before t = 0 (lead-in).
LEAD_STEPS = 40
#: Solver iterations per step.
ITERATIONS = 20
#: Default steps per revolution.
N_STEPS = 1440


def simulate_pymunk(design: np.ndarray, mechanism: SliderCrank, n_steps: int = N_STEPS,
                    iterations: int = ITERATIONS, lead_steps: int = LEAD_STEPS, extrapolate: bool = True
                    ) -> SliderCrankResult:
    """Motor torque of one design over one revolution, from a pymunk motion simulation.

    Parameters
    ----------
    design : (3,) array_like
        r, l, h in mm.
    mechanism : SliderCrank
        The fixed part of the mechanism; ``slider_mass`` must be > 0 (pymunk bodies need a mass).
    n_steps : int
        Steps per revolution (rounded up to even).
    iterations : int
        pymunk solver iterations per step.
    lead_steps : int
        Steps of the prescribed motion before t = 0.
    extrapolate : bool
        Combine with a run at twice the step (Richardson); the curve is then reported on every other step.

    Returns
    -------
    SliderCrankResult

    Raises
    ------
    InfeasibleDesignError
        If the crank cannot turn fully.
    InputError
        For a massless slider, or a massless rod given an inertia.
    """
    start = time.perf_counter()
    design = check_design(design)
    m = require_assemblable(design, mechanism.ta_limits_deg)
    if mechanism.slider_mass <= 0:
        raise InputError("the pymunk engine needs slider_mass > 0 kg (every pymunk body needs a mass)")
    if mechanism.rod_mass <= 0 and mechanism.rod_inertia:
        raise InputError("rod_inertia > 0 with rod_mass = 0: a massless rod has no inertia")
    n_steps = int(n_steps) + int(n_steps) % 2
    t = mechanism.motion.time_grid(n_steps)
    dt = float(t[1] - t[0])
    tau, theta, x = _run(design, mechanism, dt, n_steps + 1, iterations, lead_steps)
    if extrapolate:
        coarse, _, _ = _run(design, mechanism, 2 * dt, n_steps // 2 + 1, iterations, lead_steps)
        t, tau, theta, x = t[::2], 2.0 * tau[::2] - coarse, theta[::2], x[::2]
    return SliderCrankResult(
        design=design, engine="pymunk", t=t, tau=tau, theta=theta, x=x, t_rms=rms_over_cycle(t, tau),
        t_max=float(np.max(np.abs(tau))), margins=dict(zip(COLUMNS, map(float, m), strict=True)), dt=dt,
        wall_time_s=time.perf_counter() - start)


def _state(design_m, mechanism, theta, thd):
    """Positions and velocities (SI) of A, B, G, the rod angle and rate, for crank angle θ and rate θ̇."""
    r, l, h = design_m
    c, s = np.cos(theta), np.sin(theta)
    ok, x, x1, _, phi, phi1, _ = _slider_kernel(r, l, h, c, s, mechanism.branch)
    a = np.array([r * c, r * s])
    b = np.array([x, h])
    cg = mechanism.rod_com
    g = a + cg * (b - a)
    va = np.array([-r * s, r * c]) * thd
    vb = np.array([x1 * thd, 0.0])
    return a, b, g, (1 - cg) * va + cg * vb, vb, phi, phi1 * thd


def _run(design, mechanism, dt, n, iterations, lead_steps):
    """Run ``lead_steps`` + ``n`` steps; return τ (N·m), θ (rad), x (mm) at t_k = k dt, k = 0..n−1."""
    motion = mechanism.motion
    tk = (np.arange(-lead_steps, n + 1)) * dt
    theta_ref, thd_ref, _ = motion(tk)
    space, stator, crank, slider, motor = _build_space(design * MM, mechanism, iterations, theta_ref[0], thd_ref[0])
    slider.velocity_func = _slider_velocity_func(mechanism)
    target = _drive_to_target(motor, crank, dt)

    inv_dt = 1.0 / dt
    tau = np.empty(n)
    theta = np.empty(n)
    x = np.empty(n)
    for j in range(lead_steps + n):
        target[0] = theta_ref[j + 1]
        space.step(dt)
        k_rec = j - lead_steps
        if k_rec >= 0:
            tau[k_rec] = -STATOR_MOMENT * stator.angular_velocity * inv_dt
            theta[k_rec] = crank.angle
            x[k_rec] = slider.position.x / MM
        stator.angular_velocity = 0.0
        stator.angle = 0.0
    return tau, theta, x


def _build_space(design_m, mechanism, iterations, theta0, thd0):
    """The space with stator, crank, slider (and rod) moving as the prescribed motion at crank angle θ0, rate θ̇0.

    Returns the space, the stator, crank and slider bodies and the (still idle) motor between crank and stator.
    """
    r, l, h = design_m
    a0, b0, g0, vg, vb, phi0, phid = _state(design_m, mechanism, theta0, thd0)
    space = pymunk.Space()
    space.gravity = (0.0, -mechanism.gravity)
    space.damping = 1.0
    space.iterations = iterations
    space.sleep_time_threshold = float("inf")
    ground = space.static_body

    stator = pymunk.Body(PIN_MASS, STATOR_MOMENT)
    crank = pymunk.Body(PIN_MASS, mechanism.j0 if mechanism.j0 > 0 else 1e-9)
    crank.angle = float(theta0)
    crank.angular_velocity = float(thd0)
    slider = pymunk.Body(mechanism.slider_mass, 1.0)
    slider.position = tuple(b0)
    slider.velocity = tuple(vb)
    space.add(stator, crank, slider)
    # The groove spans the whole stroke with room to spare: x stays within r + l of O.
    reach = r + l
    joints = [
        pymunk.PivotJoint(ground, stator, (0.0, 0.0)),
        pymunk.PivotJoint(ground, crank, (0.0, 0.0)),
        pymunk.GrooveJoint(ground, slider, (-2 * reach, h), (2 * reach, h), (0.0, 0.0)),
    ]
    if mechanism.rod_mass > 0:
        rod = pymunk.Body(mechanism.rod_mass, mechanism.rod_inertia_si(l))
        rod.position = tuple(g0)
        rod.angle = float(phi0)
        rod.velocity = tuple(vg)
        rod.angular_velocity = float(phid)
        space.add(rod)
        joints += [pymunk.PivotJoint(crank, rod, tuple(a0)), pymunk.PivotJoint(rod, slider, tuple(b0))]
    else:
        # A massless rod is a two-force member: a distance joint between the pins is exactly that.
        local_a = (r * np.cos(0.0), 0.0)
        joints.append(pymunk.PinJoint(crank, slider, local_a, (0.0, 0.0)))
    # Chipmunk's motor enforces ω_b − ω_a = −rate: with a = crank and b = the (resting) stator, ω_crank = rate.
    motor = pymunk.SimpleMotor(crank, stator, 0.0)
    space.add(*joints, motor)
    return space, stator, crank, slider, motor


def _slider_velocity_func(mechanism):
    """The slider's ``velocity_func``: gravity plus the spring and the external force on it."""
    k = mechanism.spring_k / MM
    x_free = mechanism.spring_free_mm * MM
    force = mechanism.force
    mass = mechanism.slider_mass

    def slider_velocity(body, gravity, damping, step):
        # Called after the positions of this step are updated: the spring acts at the current slider position.
        f = -k * (body.position.x - x_free) + force
        pymunk.Body.update_velocity(body, (gravity[0] + f / mass, gravity[1]), damping, step)

    return slider_velocity


def _drive_to_target(motor, crank, dt):
    """Set the motor's rate before every solve so the crank lands on ``target[0]`` (rad) at the end of the step.

    Returns the one-element list ``target``, which the caller updates before each step.
    """
    target = [0.0]
    inv_dt = 1.0 / dt

    def drive(_constraint, _space):
        motor.rate = (target[0] - crank.angle) * inv_dt

    motor.pre_solve = drive
    return target
