"""Exudyn multibody simulation of the four-bar: a third engine next to the analytic and the pymunk ones.

The model is a planar rigid multibody system in SI units:

* crank (motor + gearbox + crank, J0 about O) and rocker (rocker + beam, I_r about C): ``RigidBody2D`` bodies whose
  centres of mass sit on their pivots, held there by ``JointRevolute2D`` joints to ground;
* the coupler: a ``ConnectorDistance`` between the pins A and B when it is light (a massless two-force member), a
  uniform bar body (m_c, m_c |AB|²/12 about its middle) with revolute joints at A and B when it has mass;
* the motor: a ``CoordinateConstraint`` on the crank's rotation coordinate that prescribes θ(t) = θ(ψ(t)) from the
  closed-form kinematics, so that the rocker follows the prescribed ψ(t) (as in the paper's two-pass CAD
  simulation).  Exudyn's equations of motion read M q̈ + g_qᵀ λ = f and g = φ_crank − UF(t) has ∂g/∂φ = 1, so
  the torque the constraint exerts on the crank, the motor torque in the sense of increasing θ, is τ = −λ;
* the rocker load: a ``CoordinateSpringDamper`` between ground and the rocker's rotation coordinate whose force is
  M_r(ψ) at the rocker's *current* angle; the spring acts on its second coordinate with −f, i.e. the load −M_r
  that the motor has to overcome.

The drive's θ(t), θ̇(t) and the load M_r(ψ) are Python user functions that call the numba kernels the other engines
use (:mod:`.motion`, :mod:`.kinematics`, :mod:`.load`).  Exudyn's symbolic user functions were measured slower here
(≈ 2× per run): Exudyn evaluates an expression as a tree, so the closed-form crank velocity, whose ψ(t) subtree is
needed a dozen times, costs more than one compiled call.

**Solver.**  Trapezoidal rule (Newmark β = 1/4, γ = 1/2, no numerical damping) with index-2 (velocity-level)
constraints and full Newton.  The default index-3 generalised-α solver makes the constraint force oscillate from
step to step and is not used.  The torque error is O(dt²) (measured: T_RMS within ~2e-5 of the analytic engine at
2 ms, ÷4 per halving).  Richardson extrapolation with a run at twice the step was tried and made it worse (the
multiplier's error is not a smooth c(t)·dt²), so there is a single run.

**Guards.**  The index-2 solver integrates velocities, lets positions drift, and reports success even for a loop
that cannot close.  Each design is therefore checked with :func:`.feasibility.require_movable` before the run, and
after it the loop closure ||B − A| − |AB||, the pins O and C and the crank angle are compared with the closed form.

Exudyn is imported inside :func:`simulate_exudyn` (it is heavy).  Each call builds its own ``SystemContainer`` and
writes no file (solution file off, sensors stored in memory), so calls in several processes do not interfere.
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit

from mechopt.errors import InputError, MechoptError
from mechopt.sim.four_bar.analytic import MM
from mechopt.sim.four_bar.feasibility import require_movable
from mechopt.sim.four_bar.kinematics import _crank_kernel, check_design, crank_angle
from mechopt.sim.four_bar.load import _load_at
from mechopt.sim.four_bar.mechanism import FourBar
from mechopt.sim.four_bar.motion import _psi_at
from mechopt.sim.four_bar.result import SimulationResult, rms_over_cycle

#: Default steps per cycle: a 2 ms step for the ventilator's 0.4 s cycle.
N_STEPS = 200
#: Mass of the crank and rocker bodies (kg): their centres of mass sit on the pivots and never move.
PIN_MASS = 1.0
#: Inertia given to a link declared without any (kg·m²), so that its body's mass matrix stays regular.
TINY_INERTIA = 1e-9
#: Largest accepted drift of the loop closure and the pins (relative to |OA|) and of the crank angle (rad) after a
#: run.  The drift is O(dt²): measured ≤ 7e-5 at 200 steps per cycle (ventilator, near-boundary designs included),
#: 1e-3 at 50, 7e-3 at 20.
CLOSURE_TOL = 1e-3


@njit(cache=True)
def _drive_angle(t, p):
    """θ(t) − θ0 of the drive (rad), ``p`` from :func:`_drive_params`; θ is taken within ±π of θ_mid."""
    psi, _, _ = _psi_at(int(p[0]), p[1], p[2], p[3], t)
    _, ax, ay, _, _ = _crank_kernel(p[4], p[5], p[6], p[7], p[8], np.cos(psi), np.sin(psi), int(p[9]))
    cm = np.cos(p[10])
    sm = np.sin(p[10])
    return np.arctan2(cm * ay - sm * ax, cm * ax + sm * ay) + p[10] - p[11]


@njit(cache=True)
def _drive_rate(t, p):
    """θ̇(t) of the drive (rad/s), ``p`` from :func:`_drive_params`."""
    psi, psi_dot, _ = _psi_at(int(p[0]), p[1], p[2], p[3], t)
    _, _, _, dtheta, _ = _crank_kernel(p[4], p[5], p[6], p[7], p[8], np.cos(psi), np.sin(psi), int(p[9]))
    return dtheta * psi_dot


def _drive_params(design_m: np.ndarray, mechanism: FourBar, theta0: float, theta_mid: float) -> np.ndarray:
    """Everything the drive kernels need as one float array (lengths in m, angles in rad)."""
    m = mechanism.motion
    xc, yc = (v * MM for v in mechanism.pivot_c)
    return np.array([m.code, m.psi_start, m.psi_end, m.t_stroke, *design_m, xc, yc, mechanism.branch,
                     theta_mid, theta0], dtype=float)


def _import_exudyn():
    try:
        import exudyn
        import exudyn.itemInterface as items
    except ImportError as exc:
        raise InputError(f"engine 'exudyn' needs the exudyn package, which cannot be imported ({exc})") from None
    return exudyn, items


def simulate_exudyn(
    design: np.ndarray | tuple[float, float, float],
    mechanism: FourBar,
    n_steps: int = N_STEPS,
) -> SimulationResult:
    """Motor torque of one design over one cycle, from an Exudyn rigid multibody simulation.

    Parameters
    ----------
    design : (3,) array_like
        |OA|, |AB|, |BC| in mm.
    mechanism : FourBar
        The fixed part of the mechanism (pivot C, inertias, coupler mass, load, motion).
    n_steps : int
        Time steps per cycle, >= 20; 200 is a 2 ms step for the ventilator's 0.4 s cycle.

    Returns
    -------
    SimulationResult
        Signed motor torque τ(t) (N·m, positive in the sense of increasing θ) on the n_steps + 1 step times,
        T_RMS and T_max (N·m), margins, the step ``dt`` (s).

    Raises
    ------
    InfeasibleDesignError
        If the design cannot be driven through the stroke (checked before the run: the index-2 solver would report
        success for a loop that cannot close).
    InputError
        If exudyn cannot be imported, ``n_steps`` is not an integer >= 20, or the crank would sweep a full turn.
    MechoptError
        If Exudyn's solver fails or the run drifts from the closed loop by more than :data:`CLOSURE_TOL`.
    """
    start = time.perf_counter()
    design = check_design(design)
    if isinstance(n_steps, bool) or not isinstance(n_steps, int | np.integer) or n_steps < 20:
        raise InputError(f"n_steps = {n_steps!r}: expected an integer >= 20 steps per cycle")
    report = require_movable(design, mechanism)
    exudyn_modules = _import_exudyn()
    t = mechanism.motion.time_grid(n_steps)
    psi_ref, _, _ = mechanism.motion(t)
    theta_ref = np.unwrap(crank_angle(design, mechanism.pivot_c, psi_ref, mechanism.branch)[0])
    if np.ptp(theta_ref) >= 1.9 * np.pi:
        raise InputError(f"design {design.tolist()} mm: the crank sweeps {np.degrees(np.ptp(theta_ref)):.0f}°, "
                         "more than the Exudyn drive follows (< 342°)")
    tau, theta, psi = _run(exudyn_modules, design * MM, mechanism, t, theta_ref, psi_ref)
    return SimulationResult(
        design=design, engine="exudyn", t=t, tau=tau, theta=theta, psi=psi,
        t_rms=rms_over_cycle(t, tau), t_max=float(np.max(np.abs(tau))),
        margins=report.margins(0), feasible=bool(report.feasible[0]), message=report.message(0),
        dt=float(t[1] - t[0]), wall_time_s=time.perf_counter() - start,
    )


def _run(exudyn_modules, design_m: np.ndarray, mechanism: FourBar, t: np.ndarray, theta_ref: np.ndarray,
         psi_ref: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Build the multibody system, integrate one cycle on the uniform grid ``t``; return τ, θ, ψ there."""
    exu, items = exudyn_modules
    xc, yc = (v * MM for v in mechanism.pivot_c)
    psi0 = float(psi_ref[0])
    theta0 = float(theta_ref[0])
    theta_mid = 0.5 * (float(np.min(theta_ref)) + float(np.max(theta_ref)))

    sc = exu.SystemContainer()  # owns the system: it must outlive every call on ``mbs``
    mbs = sc.AddSystem()
    ground = mbs.AddObject(items.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
    ground_node = mbs.AddNode(items.NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    ground_coord = mbs.AddMarker(items.MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))
    crank_node, rocker_node = _add_linkage(mbs, items, ground, design_m, mechanism, theta0, psi0)
    params = _drive_params(design_m, mechanism, theta0, theta_mid)
    drive = _add_drive_and_load(mbs, items, ground_coord, crank_node, rocker_node, params, mechanism, psi0)
    sensors = _add_sensors(mbs, exu, items, drive, crank_node, rocker_node)
    mbs.Assemble()

    _solve(exu, mbs, _solver_settings(exu, t))
    force, crank_q, rocker_q = _stored_on_grid(mbs, sensors, t)
    tau = -force[:, 1]
    theta = theta0 + crank_q[:, 3]
    psi = psi0 + rocker_q[:, 3]
    _check_closure(design_m, (xc, yc), theta, psi, crank_q, rocker_q, theta_ref)
    return tau, theta, psi


def _add_body(mbs, items, position, angle: float, mass: float, inertia: float) -> tuple[int, int]:
    """A rigid body (SI) with its centre of mass at ``position`` and reference angle ``angle``; its node and object."""
    node = mbs.AddNode(items.NodeRigidBody2D(referenceCoordinates=[position[0], position[1], angle]))
    return node, mbs.AddObject(items.ObjectRigidBody2D(nodeNumber=node, mass=mass, inertia=inertia))


def _pin(mbs, items, body0: int, local0, body1: int, local1) -> list[int]:
    """The two position markers of a pin joint between two bodies."""
    # Local positions are in the body frames, whose reference angles are θ0, ψ0 and the coupler's φ0.
    return [mbs.AddMarker(items.MarkerBodyPosition(bodyNumber=b, localPosition=[p[0], p[1], 0.0]))
            for b, p in ((body0, local0), (body1, local1))]


def _add_linkage(mbs, items, ground: int, design_m: np.ndarray, mechanism: FourBar, theta0: float,
                 psi0: float) -> tuple[int, int]:
    """Crank and rocker pinned to ground, joined by the coupler (a bar body or a distance); their nodes."""
    oa, ab, bc = (float(v) for v in design_m)
    xc, yc = (v * MM for v in mechanism.pivot_c)
    a0 = np.array([oa * np.cos(theta0), oa * np.sin(theta0)])
    b0 = np.array([xc + bc * np.cos(psi0), yc + bc * np.sin(psi0)])
    crank_node, crank = _add_body(mbs, items, (0.0, 0.0), theta0, PIN_MASS,
                                  mechanism.j0 if mechanism.j0 > 0 else TINY_INERTIA)
    rocker_node, rocker = _add_body(mbs, items, (xc, yc), psi0, PIN_MASS,
                                    mechanism.i_r if mechanism.i_r > 0 else TINY_INERTIA)
    mbs.AddObject(items.ObjectJointRevolute2D(markerNumbers=_pin(mbs, items, ground, (0.0, 0.0), crank, (0.0, 0.0))))
    mbs.AddObject(items.ObjectJointRevolute2D(markerNumbers=_pin(mbs, items, ground, (xc, yc), rocker, (0.0, 0.0))))
    if mechanism.coupler_mass > 0:
        mc = mechanism.coupler_mass
        phi0 = float(np.arctan2(b0[1] - a0[1], b0[0] - a0[0]))
        _, coupler = _add_body(mbs, items, 0.5 * (a0 + b0), phi0, mc, mc * ab * ab / 12.0)
        mbs.AddObject(items.ObjectJointRevolute2D(
            markerNumbers=_pin(mbs, items, crank, (oa, 0.0), coupler, (-0.5 * ab, 0.0))))
        mbs.AddObject(items.ObjectJointRevolute2D(
            markerNumbers=_pin(mbs, items, coupler, (0.5 * ab, 0.0), rocker, (bc, 0.0))))
    else:
        mbs.AddObject(items.ObjectConnectorDistance(markerNumbers=_pin(mbs, items, crank, (oa, 0.0), rocker, (bc, 0.0)),
                                                    distance=ab))
    return crank_node, rocker_node


def _add_drive_and_load(mbs, items, ground_coord: int, crank_node: int, rocker_node: int, params: np.ndarray,
                        mechanism: FourBar, psi0: float) -> int:
    """The motor (θ(t) prescribed on the crank) and the rocker load M_r(ψ); returns the motor's constraint."""
    breaks, coefs = mechanism.load.breaks, mechanism.load.coefs
    crank_coord = mbs.AddMarker(items.MarkerNodeCoordinate(nodeNumber=crank_node, coordinate=2))
    rocker_coord = mbs.AddMarker(items.MarkerNodeCoordinate(nodeNumber=rocker_node, coordinate=2))
    drive = mbs.AddObject(items.CoordinateConstraint(
        markerNumbers=[ground_coord, crank_coord],
        offsetUserFunction=lambda _mbs, time_s, _item, _offset: _drive_angle(time_s, params),
        offsetUserFunction_t=lambda _mbs, time_s, _item, _offset: _drive_rate(time_s, params),
    ))
    mbs.AddObject(items.CoordinateSpringDamper(
        markerNumbers=[ground_coord, rocker_coord], stiffness=0.0, damping=0.0,
        springForceUserFunction=lambda _mbs, _t, _item, u, _v, _k, _d, _off: _load_at(breaks, coefs, psi0 + u),
    ))
    return drive


def _add_sensors(mbs, exu, items, drive: int, crank_node: int, rocker_node: int) -> list[int]:
    """In-memory sensors of the motor's constraint force and of the crank's and rocker's coordinates."""
    stored = {"storeInternal": True, "writeToFile": False}
    return [
        mbs.AddSensor(items.SensorObject(objectNumber=drive, outputVariableType=exu.OutputVariableType.Force,
                                         **stored)),
        mbs.AddSensor(items.SensorNode(nodeNumber=crank_node, outputVariableType=exu.OutputVariableType.Coordinates,
                                       **stored)),
        mbs.AddSensor(items.SensorNode(nodeNumber=rocker_node, outputVariableType=exu.OutputVariableType.Coordinates,
                                       **stored)),
    ]


def _solver_settings(exu, t: np.ndarray):
    """Trapezoidal rule (Newmark β = 1/4, γ = 1/2) with index-2 constraints and full Newton, fixed steps on ``t``."""
    n_steps = t.size - 1
    dt = float(t[-1] - t[0]) / n_steps
    settings = exu.SimulationSettings()
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = 0.5 * dt  # < dt: a sample after every step
    settings.show.globalTimers = False
    ti = settings.timeIntegration
    ti.startTime = float(t[0])
    ti.endTime = float(t[-1])
    ti.numberOfSteps = n_steps
    ti.verboseMode = 0
    ti.adaptiveStep = False
    ti.automaticStepSize = False
    ti.newton.useModifiedNewton = False
    ti.generalizedAlpha.useNewmark = True
    ti.generalizedAlpha.useIndex2Constraints = True
    ti.generalizedAlpha.newmarkBeta = 0.25
    ti.generalizedAlpha.newmarkGamma = 0.5
    return settings


def _solve(exu, mbs, settings) -> None:
    """Integrate; any failure of Exudyn's solver becomes a one-line :class:`MechoptError`."""
    try:
        ok = mbs.SolveDynamic(settings, solverType=exu.DynamicSolverType.TrapezoidalIndex2)
    except Exception as exc:  # Exudyn raises its own error types; the user gets one line
        raise MechoptError(f"Exudyn failed: {' '.join(str(exc).split())[:300]}") from None
    if not ok:
        raise MechoptError("Exudyn's solver did not converge")


def _stored_on_grid(mbs, sensors: list[int], t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sensors' stored rows (time first), checked to be one per step time of ``t``."""
    force, crank_q, rocker_q = (mbs.GetSensorStoredData(s) for s in sensors)
    if force.shape[0] != t.size or np.max(np.abs(force[:, 0] - t)) > 1e-9 * t[-1]:
        raise MechoptError(f"Exudyn stored {force.shape[0]} samples, expected {t.size} on the time grid")
    return force, crank_q, rocker_q


def _check_closure(design_m, pivot_m, theta, psi, crank_q, rocker_q, theta_ref) -> None:
    """Raise if the run left the closed loop: the index-2 solver keeps velocities, not positions, consistent."""
    oa, ab, bc = design_m
    xc, yc = pivot_m
    gap = np.hypot(xc + bc * np.cos(psi) - oa * np.cos(theta), yc + bc * np.sin(psi) - oa * np.sin(theta)) - ab
    drifts = {
        "loop closure ||AB| - |AB|_0|": np.max(np.abs(gap)) / oa,
        "pin O": np.max(np.hypot(crank_q[:, 1], crank_q[:, 2])) / oa,
        "pin C": np.max(np.hypot(rocker_q[:, 1], rocker_q[:, 2])) / oa,
        "crank angle": np.max(np.abs(theta - theta_ref)),
    }
    worst = max(drifts, key=drifts.get)
    if not drifts[worst] <= CLOSURE_TOL:
        raise MechoptError(f"Exudyn run drifted off the closed loop: {worst} off by {drifts[worst]:.2e} "
                           f"(tolerance {CLOSURE_TOL:g}); use more steps per cycle (n_steps)")
