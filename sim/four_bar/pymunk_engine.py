"""pymunk rigid-body motion simulation of a four-bar: the stand-in for the paper's CAD motion simulation.

As in the paper (Fig. 5) each design is simulated twice: a kinematic pass computes the crank motion θ(t) that makes
the rocker follow ψ(t) (closed form, :mod:`sim.kinematics`), and a dynamic pass imposes θ(t) on the crank and records
the motor torque.  The dynamic pass is a pymunk space (SI units) with

* bodies crank (motor + crank, J0 about O) and rocker (rocker + beam, I_r about C), pinned at O and C; the coupler is
  a uniform-bar body pinned at A and B when it has mass, and a distance joint A–B (a massless two-force member) when
  it has none; no shapes (adjacent links would collide at the pins);
* a ``SimpleMotor`` between a *stator* body and the crank, whose rate is set inside every step (``pre_solve``, after
  pymunk has moved the bodies) to (θ(t_{k+1}) − θ_k)/dt: position feedback that lands the crank on the prescribed
  angle at every step;
* the rocker load −M_r(ψ) applied by a ``DampedRotarySpring`` whose ``torque_func`` reads the rocker's current angle,
  so the load is evaluated inside the step, not from the previous step's angle.

**Signed torque.**  pymunk reports a constraint's impulse unsigned.  The stator is a dynamic body pivoted at O on its
centre of mass, so the only angular impulse it receives is the motor's reaction: τ = −I_s ω_s / dt after each step
(the stator is reset to rest afterwards).  This is the cradle-mounted motor of a torque dynamometer; pymunk's own
``impulse`` is checked against its magnitude.

**Step size.**  The recorded torque's error grows linearly with dt (pymunk solves the constraint velocities at the
start-of-step pose) and with the crank's higher derivatives, sharply near a poor transmission angle.  The step is
chosen per design from the kinematic pass (:func:`choose_step`), and a second run at twice the step removes the
first-order term by Richardson extrapolation.
"""

from __future__ import annotations

import time

import numpy as np
import pymunk

from mechopt.sim.four_bar.analytic import MM
from mechopt.sim.four_bar.feasibility import require_movable
from mechopt.sim.four_bar.kinematics import check_design, crank_angle
from mechopt.sim.four_bar.load import _load_at
from mechopt.sim.four_bar.mechanism import FourBar
from mechopt.sim.four_bar.result import SimulationResult, rms_over_cycle

#: Moment of inertia of the stator (kg·m²): large, so that it barely turns within one step, yet its angular velocity
#: keeps ~13 significant digits of the motor's reaction impulse.
STATOR_MOMENT = 1.0e3
#: Mass of the bodies pinned at their centre of mass (crank, rocker, stator), kg: it never accelerates, so it adds no
#: torque, and a mass of the order of the links' effective masses keeps the iterative solver well conditioned.
PIN_MASS = 1.0
#: Steps at the start pose before recording, so the solver's cold start does not pollute the record.
HOLD_STEPS = 40
#: Solver iterations per step.
ITERATIONS = 20


def choose_step(design: np.ndarray, mechanism: FourBar, rel_tol: float = 0.005) -> int:
    """Number of steps per cycle for a design, from its kinematics only.

    The torque recorded is driven by the finite-difference crank acceleration, whose error is ≈ dt²/12 · θ⁗(t);
    the error relative to the torque's size is estimated from θ(t) on a fine grid, and the step is chosen so that
    it stays a small fraction of ``rel_tol``.  The count is a smooth function of the design rounded up to an integer,
    so neighbouring designs get nearly equal steps (no jumps in the error).

    Parameters
    ----------
    design : (3,) ndarray
        |OA|, |AB|, |BC| in mm.
    mechanism : FourBar
        The mechanism.
    rel_tol : float
        Target relative error of T_RMS.

    Returns
    -------
    int
        Steps per cycle.
    """
    motion = mechanism.motion
    t = motion.time_grid(2000)
    h = t[1] - t[0]
    psi, psid, psidd = motion(t)
    _, t1, t2 = crank_angle(design, mechanism.pivot_c, psi, mechanism.branch)
    theta_dd = t2 * psid**2 + t1 * psidd
    fourth = np.gradient(np.gradient(theta_dd, h), h)
    scale = np.sqrt(np.mean(theta_dd**2))
    ratio = np.sqrt(np.mean(fourth**2)) / scale if scale > 0 else 0.0
    # dt²/12 · ratio <= rel_tol / 8, the factor 8 leaving room for the solver's own error.
    dt = np.sqrt(12.0 * rel_tol / 8.0 / max(ratio, 1e-12))
    return int(np.clip(np.ceil(motion.period / dt), 200, 20000))


def simulate_pymunk(
    design: np.ndarray,
    mechanism: FourBar,
    n_steps: int | None = None,
    rel_tol: float = 0.005,
    iterations: int = ITERATIONS,
    hold_steps: int = HOLD_STEPS,
    extrapolate: bool = True,
) -> SimulationResult:
    """Motor torque of one design over one cycle, from a pymunk motion simulation.

    Parameters
    ----------
    design : (3,) array_like
        |OA|, |AB|, |BC| in mm.
    mechanism : FourBar
        The fixed part of the mechanism.
    n_steps : int, optional
        Steps per cycle; chosen by :func:`choose_step` from ``rel_tol`` when omitted.
    rel_tol : float
        Target relative accuracy of T_RMS when the step is chosen automatically.
    iterations : int
        pymunk solver iterations per step.
    hold_steps : int
        Steps at the start pose before recording.
    extrapolate : bool
        Combine the run with one at twice the step (Richardson extrapolation of the first-order error); the torque
        curve is then reported on every other step.

    Returns
    -------
    SimulationResult
        Signed torque curve (N·m), T_RMS, T_max and the margins.

    Raises
    ------
    InfeasibleDesignError
        If the design cannot be driven through the stroke.
    """
    start = time.perf_counter()
    design = check_design(design)
    report = require_movable(design, mechanism)
    if n_steps is None:
        n_steps = choose_step(design, mechanism, rel_tol)
    n_steps = int(n_steps) + int(n_steps) % 2
    motion = mechanism.motion
    t = motion.time_grid(n_steps)
    psi_ref, _, _ = motion(t)
    theta_ref = np.unwrap(crank_angle(design, mechanism.pivot_c, psi_ref, mechanism.branch)[0])
    dt = float(t[1] - t[0])
    tau, theta, psi, impulse = _run(design * MM, mechanism, theta_ref, psi_ref[0], dt, iterations, hold_steps)
    if extrapolate:
        # pymunk's integrator makes the recorded torque first-order accurate in dt (constraint velocities are solved
        # at the start-of-step pose).  A second run at twice the step, on every other grid point, cancels that
        # term (Richardson): the error drops from ~1e-3 to ~1e-5 relative for 1.5 times the cost.
        coarse, *_ = _run(design * MM, mechanism, theta_ref[::2], psi_ref[0], 2 * dt, iterations, hold_steps)
        t, tau, theta, psi = t[::2], 2.0 * tau[::2] - coarse, theta[::2], psi[::2]
    return SimulationResult(
        design=design, engine="pymunk", t=t, tau=tau, theta=theta, psi=psi,
        t_rms=rms_over_cycle(t, tau), t_max=float(np.max(np.abs(tau))),
        margins=report.margins(0), feasible=bool(report.feasible[0]), message=report.message(0),
        dt=dt, wall_time_s=time.perf_counter() - start,
    )


def _build_space(design_m, mechanism, theta0, psi0, iterations):
    """The mechanism at its start pose as pymunk bodies and joints; return the space, the stator, the crank, the
    rocker and the crank's motor (its rate still zero)."""
    oa, ab, bc = design_m
    xc, yc = (v * MM for v in mechanism.pivot_c)
    a0 = (oa * np.cos(theta0), oa * np.sin(theta0))
    b0 = (xc + bc * np.cos(psi0), yc + bc * np.sin(psi0))

    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    space.damping = 1.0
    space.iterations = iterations
    ground = space.static_body

    stator = pymunk.Body(PIN_MASS, STATOR_MOMENT)
    stator.position = (0.0, 0.0)
    crank = pymunk.Body(PIN_MASS, mechanism.j0 if mechanism.j0 > 0 else 1e-9)
    crank.position = (0.0, 0.0)
    crank.angle = theta0
    rocker = pymunk.Body(PIN_MASS, mechanism.i_r if mechanism.i_r > 0 else 1e-9)
    rocker.position = (xc, yc)
    space.add(stator, crank, rocker)
    joints = [
        pymunk.PivotJoint(ground, stator, (0.0, 0.0)),
        pymunk.PivotJoint(ground, crank, (0.0, 0.0)),
        pymunk.PivotJoint(rocker, ground, (xc, yc)),
    ]
    if mechanism.coupler_mass > 0:
        coupler = pymunk.Body(mechanism.coupler_mass, mechanism.coupler_mass * ab * ab / 12.0)
        coupler.position = ((a0[0] + b0[0]) / 2, (a0[1] + b0[1]) / 2)
        space.add(coupler)
        joints += [pymunk.PivotJoint(crank, coupler, a0), pymunk.PivotJoint(coupler, rocker, b0)]
    else:
        # A light coupler is a two-force member: a distance joint between the pins A and B is exactly that, and it
        # spares the iterative solver a nearly massless body between two heavy ones (which it converges on badly).
        joints.append(pymunk.PinJoint(crank, rocker, (oa, 0.0), (b0[0] - xc, b0[1] - yc)))
    # Chipmunk's motor enforces ω_b − ω_a = −rate: with a = crank and b = the (resting) stator, ω_crank = rate.
    motor = pymunk.SimpleMotor(crank, stator, 0.0)
    # The spring's torque on its body b (the rocker) is torque_func(a.angle − b.angle) = −M_r(ψ): the load that the
    # motor has to overcome.  Zero stiffness and damping: only the custom torque acts.
    load = pymunk.DampedRotarySpring(ground, rocker, 0.0, 0.0, 0.0)
    breaks, coefs = mechanism.load.breaks, mechanism.load.coefs
    load.torque_func = lambda _spring, rel_angle: -_load_at(breaks, coefs, psi0 - rel_angle)
    space.add(*joints, motor, load)
    return space, stator, crank, rocker, motor


def _run(design_m, mechanism, theta_ref, psi0, dt, iterations, hold_steps):
    """Build the space, hold the start pose, run one cycle; return τ, θ, ψ and pymunk's |impulse|/dt per step."""
    theta0 = float(theta_ref[0])
    space, stator, crank, rocker, motor = _build_space(design_m, mechanism, theta0, psi0, iterations)
    target = [theta0]
    inv_dt = 1.0 / dt

    def drive(_constraint, _space):
        # Called after pymunk has moved the bodies to this step's pose: land the crank on the next target angle.
        motor.rate = (target[0] - crank.angle) * inv_dt

    motor.pre_solve = drive

    n = theta_ref.size
    tau = np.empty(n)
    impulse = np.empty(n)
    theta = np.empty(n)
    psi = np.empty(n)
    for _ in range(hold_steps):
        space.step(dt)
        stator.angular_velocity = 0.0
        stator.angle = 0.0
    for k in range(n):
        # The solve of this call sees the pose at t_k and sets the velocity over [t_k, t_{k+1}].
        target[0] = theta_ref[k + 1] if k + 1 < n else 2 * theta_ref[k] - theta_ref[k - 1]
        space.step(dt)
        tau[k] = -STATOR_MOMENT * stator.angular_velocity * inv_dt
        impulse[k] = motor.impulse * inv_dt
        theta[k] = crank.angle
        psi[k] = psi0 + rocker.angle
        stator.angular_velocity = 0.0
        stator.angle = 0.0
    return tau, theta, psi, impulse
