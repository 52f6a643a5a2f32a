"""The flexible slider-crank in Exudyn: a geometrically exact ANCF cable rod, the independent check of the modal model.

Model: a rigid crank (``NodeRigidBody2D``) pinned to the ground at O and turned at the constant rate ω by a
velocity-level coordinate constraint; the rod as ``n_elements`` ``ObjectANCFCable2D`` elements (EA, EI, ρA of the
section; bending and axial damping β·EI and β·EA, the Kelvin-Voigt damping of :mod:`.parameters`); a revolute joint
between the crank tip and the rod's first node; the slider a ``MassPoint2D`` on the x axis (coordinate constraint
y = 0), pinned to the rod's last node.  The rod starts straight at θ2 = 0 with the rigid-body velocity field and the
quasi-static axial strain of that instant (an unstrained rod would release the slider for the first millisecond).
Generalized-α integration with ``steps_per_sample`` steps between samples and a Newton tolerance of 1e-4 (tighter
makes the solver shrink its step without changing the answer).  No solution or sensor files are written.

V, A are the slider node's velocity and acceleration (they include the rod's axial elasticity, the modal model's do
not); D is the mid-point's distance from the chord of the deformed rod's end nodes.
"""

from __future__ import annotations

import time

import numpy as np

from mechopt.errors import InputError
from mechopt.sim.flexible.kinematics import rigid_motion
from mechopt.sim.flexible.parameters import FlexibleSliderCrank
from mechopt.sim.flexible.response import Response

__all__ = ["simulate_exudyn"]


def _initial_axial_strain(p: FlexibleSliderCrank, s: np.ndarray) -> np.ndarray:
    """Axial displacement (m) along the rod at θ2 = 0 from the quasi-static tension of that instant.

    At θ2 = 0 the rod lies on the x axis and every point accelerates along it: a(s) = a_A∥ − φ̇² s.  The tension is
    T(s) = T_B − ρA ∫_s^L a ds' with T_B = −m a_B; integrating T / EA from A gives the displacement.
    """
    m0 = rigid_motion(p.l2, p.l3, p.omega, np.array([0.0]))
    rho_a, ea, L = p.rho * p.area, p.E * p.area, p.l3
    a_par, phi_d2 = float(m0.aA_par[0]), float(m0.phi_d[0]) ** 2
    t_b = -p.slider_mass * float(m0.acc[0])
    # ∫_0^s T ds' with T(s') = t_b − ρA [a_par (L − s') − φ̇² (L² − s'²) / 2]
    integral = (t_b * s - rho_a * (a_par * (L * s - 0.5 * s**2) - 0.5 * phi_d2 * (L * L * s - s**3 / 3.0)))
    return integral / ea


def _tension_slope(p: FlexibleSliderCrank, s: np.ndarray) -> np.ndarray:
    """Axial strain T(s) / EA at θ2 = 0 (the derivative of :func:`_initial_axial_strain`)."""
    m0 = rigid_motion(p.l2, p.l3, p.omega, np.array([0.0]))
    rho_a, L = p.rho * p.area, p.l3
    a_par, phi_d2 = float(m0.aA_par[0]), float(m0.phi_d[0]) ** 2
    t_b = -p.slider_mass * float(m0.acc[0])
    return (t_b - rho_a * (a_par * (L - s) - 0.5 * phi_d2 * (L * L - s * s))) / (p.E * p.area)


def simulate_exudyn(p: FlexibleSliderCrank, steps_per_sample: int = 8, newton_tolerance: float = 1e-4) -> Response:
    """Simulate one design with Exudyn's ANCF cable elements.

    Parameters
    ----------
    p : FlexibleSliderCrank
        The design and settings (SI); ``n_modes`` and ``axial_stiffening`` do not apply.
    steps_per_sample : int
        Time steps between two output samples.
    newton_tolerance : float
        Relative tolerance of the Newton iterations.

    Returns
    -------
    Response
    """
    import exudyn as exu  # lazily: importing Exudyn costs ~1 s and only this engine needs it
    from exudyn.itemInterface import (
        CoordinateConstraint,
        MarkerBodyPosition,
        MarkerBodyRigid,
        MarkerNodeCoordinate,
        MarkerNodePosition,
        MassPoint2D,
        NodePoint2D,
        NodePoint2DSlope1,
        NodePointGround,
        NodeRigidBody2D,
        ObjectANCFCable2D,
        ObjectGround,
        ObjectRigidBody2D,
        RevoluteJoint2D,
        SensorNode,
    )

    if p.n_elements % 2:
        raise InputError(f"n_elements = {p.n_elements}: the Exudyn engine needs an even number (a mid-span node)")
    start = time.perf_counter()
    r, L, w = p.l2, p.l3, p.omega
    n = p.n_elements
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    n_ground = mbs.AddNode(NodePointGround())
    m_ground_coord = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n_ground, coordinate=0))

    # crank: its inertia is irrelevant (the rate is prescribed), a small one keeps the mass matrix regular
    crank_mass = 1e-3
    n_crank = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0.0, 0.0, 0.0], initialVelocities=[0.0, 0.0, w]))
    o_crank = mbs.AddObject(ObjectRigidBody2D(mass=crank_mass, inertia=crank_mass * r * r / 3.0,
                                              nodeNumber=n_crank))
    m_o_ground = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    m_o_crank = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o_crank, localPosition=[0.0, 0.0, 0.0]))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[m_o_ground, m_o_crank]))
    m_crank_angle = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n_crank, coordinate=2))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[m_ground_coord, m_crank_angle], offset=w, velocityLevel=True))
    m_crank_tip = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o_crank, localPosition=[r, 0.0, 0.0]))

    # rod along +x from A = (r, 0) at θ2 = 0; rigid velocity field v = (0, r ω + φ̇ s), slope rate (0, φ̇)
    m0 = rigid_motion(r, L, w, np.array([0.0]))
    phi_d = float(m0.phi_d[0])
    s_nodes = np.linspace(0.0, L, n + 1)
    u_axial = _initial_axial_strain(p, s_nodes)
    strain = _tension_slope(p, s_nodes)
    nodes = []
    for s, u, eps in zip(s_nodes, u_axial, strain, strict=True):
        nodes.append(mbs.AddNode(NodePoint2DSlope1(
            referenceCoordinates=[r + s, 0.0, 1.0, 0.0],
            initialCoordinates=[u, 0.0, eps, 0.0],
            initialVelocities=[0.0, r * w + phi_d * s, 0.0, phi_d])))
    ea, ei = p.E * p.area, p.E * p.second_moment
    for e in range(n):
        mbs.AddObject(ObjectANCFCable2D(
            length=L / n, massPerLength=p.rho * p.area, bendingStiffness=ei, axialStiffness=ea,
            bendingDamping=p.beta * ei, axialDamping=p.beta * ea,
            nodeNumbers=[nodes[e], nodes[e + 1]]))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[m_crank_tip, mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[0]))]))

    # slider: a point mass on the x axis, pinned to the rod's last node
    n_slider = mbs.AddNode(NodePoint2D(referenceCoordinates=[r + L, 0.0], initialCoordinates=[u_axial[-1], 0.0]))
    o_slider = mbs.AddObject(MassPoint2D(mass=p.slider_mass, nodeNumber=n_slider))
    m_slider = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o_slider, localPosition=[0.0, 0.0, 0.0]))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1])), m_slider]))
    m_slider_y = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n_slider, coordinate=1))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[m_ground_coord, m_slider_y]))

    out = exu.OutputVariableType
    sens_v = mbs.AddSensor(SensorNode(nodeNumber=n_slider, storeInternal=True, writeToFile=False,
                                      outputVariableType=out.Velocity))
    sens_a = mbs.AddSensor(SensorNode(nodeNumber=n_slider, storeInternal=True, writeToFile=False,
                                      outputVariableType=out.Acceleration))
    sens_pos = [mbs.AddSensor(SensorNode(nodeNumber=k, storeInternal=True, writeToFile=False,
                                         outputVariableType=out.Position)) for k in nodes]
    mbs.Assemble()

    dt_out = p.t_end / (p.n_samples - 1)
    settings = exu.SimulationSettings()
    settings.timeIntegration.endTime = p.t_end
    settings.timeIntegration.numberOfSteps = steps_per_sample * (p.n_samples - 1)
    settings.timeIntegration.newton.relativeTolerance = newton_tolerance
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = dt_out
    settings.solution.file.writeInitialValues = True
    settings.show.computationTime = False
    settings.show.statistics = False
    mbs.SolveDynamic(settings)

    t = np.linspace(0.0, p.t_end, p.n_samples)

    def sampled(sensor: int) -> np.ndarray:
        data = np.asarray(mbs.GetSensorStoredData(sensor))
        # one row per write period; match rows to the sample instants by time (the first row is t = 0)
        idx = np.rint(data[:, 0] / dt_out).astype(int)
        keep = np.zeros(p.n_samples, dtype=bool)
        values = np.full((p.n_samples, data.shape[1] - 1), np.nan)
        ok = (idx >= 0) & (idx < p.n_samples) & (np.abs(data[:, 0] - idx * dt_out) < 1e-3 * dt_out)
        values[idx[ok]] = data[ok, 1:]
        keep[idx[ok]] = True
        if not keep.all():
            raise RuntimeError(f"Exudyn stored {int(keep.sum())} of {p.n_samples} samples")
        return values

    V = sampled(sens_v)[:, 0]
    A = sampled(sens_a)[:, 0]
    P = np.stack([sampled(k)[:, :2] for k in sens_pos], axis=1)  # (n_samples, n + 1, 2)
    chord = P[:, -1] - P[:, 0]
    length = np.linalg.norm(chord, axis=1)
    normal = np.stack([-chord[:, 1], chord[:, 0]], axis=1) / length[:, None]
    shape = np.einsum("tkj,tj->tk", P - P[:, :1], normal)
    return Response(t=t, V=V, A=A, D=shape[:, n // 2], s=s_nodes, shape=shape, engine="exudyn",
                    seconds=time.perf_counter() - start)

