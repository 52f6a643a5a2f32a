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
from mechopt.sim.exudyn_sampling import add_driven_crank, sampled, solver_settings
from mechopt.sim.flexible_slider_crank.kinematics import rigid_motion
from mechopt.sim.flexible_slider_crank.parameters import FlexibleSliderCrank
from mechopt.sim.flexible_slider_crank.response import Response

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
    import exudyn.itemInterface as items

    if p.n_elements % 2:
        raise InputError(f"n_elements = {p.n_elements}: the Exudyn engine needs an even number (a mid-span node)")
    start = time.perf_counter()
    sc = exu.SystemContainer()  # owns the system: it must outlive every call on ``mbs``
    mbs = sc.AddSystem()
    ground = mbs.AddObject(items.ObjectGround())
    n_ground = mbs.AddNode(items.NodePointGround())
    m_ground_coord = mbs.AddMarker(items.MarkerNodeCoordinate(nodeNumber=n_ground, coordinate=0))
    m_crank_tip = add_driven_crank(mbs, items, p.l2, p.omega, ground, m_ground_coord)
    s_nodes = np.linspace(0.0, p.l3, p.n_elements + 1)
    nodes, u_end = _add_rod(mbs, items, p, s_nodes, m_crank_tip)
    n_slider = _add_slider(mbs, items, p, nodes[-1], u_end, m_ground_coord)
    sensors = _add_sensors(mbs, items, exu.OutputVariableType, n_slider, nodes)
    mbs.Assemble()
    mbs.SolveDynamic(solver_settings(exu, p.t_end, p.n_samples, steps_per_sample, newton_tolerance))
    return _response(mbs, p, sensors, s_nodes, start)


def _add_rod(mbs, items, p: FlexibleSliderCrank, s_nodes: np.ndarray, m_crank_tip: int) -> tuple[list[int], float]:
    """The rod's cable elements, in their state at θ2 = 0, pinned to the crank tip.

    Returns the rod's node numbers (A to B) and the axial displacement (m) of its last node.
    """
    r, L, w = p.l2, p.l3, p.omega
    n = p.n_elements
    # rod along +x from A = (r, 0) at θ2 = 0; rigid velocity field v = (0, r ω + φ̇ s), slope rate (0, φ̇)
    m0 = rigid_motion(r, L, w, np.array([0.0]))
    phi_d = float(m0.phi_d[0])
    u_axial = _initial_axial_strain(p, s_nodes)
    strain = _tension_slope(p, s_nodes)
    nodes = []
    for s, u, eps in zip(s_nodes, u_axial, strain, strict=True):
        nodes.append(mbs.AddNode(items.NodePoint2DSlope1(
            referenceCoordinates=[r + s, 0.0, 1.0, 0.0],
            initialCoordinates=[u, 0.0, eps, 0.0],
            initialVelocities=[0.0, r * w + phi_d * s, 0.0, phi_d])))
    ea, ei = p.E * p.area, p.E * p.second_moment
    for e in range(n):
        mbs.AddObject(items.ObjectANCFCable2D(
            length=L / n, massPerLength=p.rho * p.area, bendingStiffness=ei, axialStiffness=ea,
            bendingDamping=p.beta * ei, axialDamping=p.beta * ea,
            nodeNumbers=[nodes[e], nodes[e + 1]]))
    mbs.AddObject(items.RevoluteJoint2D(
        markerNumbers=[m_crank_tip, mbs.AddMarker(items.MarkerNodePosition(nodeNumber=nodes[0]))]))
    return nodes, u_axial[-1]


def _add_slider(mbs, items, p: FlexibleSliderCrank, rod_end: int, u_end: float, m_ground_coord: int) -> int:
    """The slider, a point mass on the x axis pinned to the rod's last node ``rod_end``; returns its node."""
    n_slider = mbs.AddNode(items.NodePoint2D(referenceCoordinates=[p.l2 + p.l3, 0.0], initialCoordinates=[u_end, 0.0]))
    o_slider = mbs.AddObject(items.MassPoint2D(mass=p.slider_mass, nodeNumber=n_slider))
    m_slider = mbs.AddMarker(items.MarkerBodyPosition(bodyNumber=o_slider, localPosition=[0.0, 0.0, 0.0]))
    mbs.AddObject(items.RevoluteJoint2D(
        markerNumbers=[mbs.AddMarker(items.MarkerNodePosition(nodeNumber=rod_end)), m_slider]))
    m_slider_y = mbs.AddMarker(items.MarkerNodeCoordinate(nodeNumber=n_slider, coordinate=1))
    mbs.AddObject(items.CoordinateConstraint(markerNumbers=[m_ground_coord, m_slider_y]))
    return n_slider


def _add_sensors(mbs, items, out, n_slider: int, nodes: list[int]) -> tuple[int, int, list[int]]:
    """In-memory sensors of the slider's velocity and acceleration and of every rod node's position."""
    sens_v = mbs.AddSensor(items.SensorNode(nodeNumber=n_slider, storeInternal=True, writeToFile=False,
                                            outputVariableType=out.Velocity))
    sens_a = mbs.AddSensor(items.SensorNode(nodeNumber=n_slider, storeInternal=True, writeToFile=False,
                                            outputVariableType=out.Acceleration))
    sens_pos = [mbs.AddSensor(items.SensorNode(nodeNumber=k, storeInternal=True, writeToFile=False,
                                               outputVariableType=out.Position)) for k in nodes]
    return sens_v, sens_a, sens_pos


def _response(mbs, p: FlexibleSliderCrank, sensors: tuple[int, int, list[int]], s_nodes: np.ndarray,
              start: float) -> Response:
    """V, A of the slider and the rod's deflection from its end-node chord, from the solved system's sensors."""
    sens_v, sens_a, sens_pos = sensors
    t = np.linspace(0.0, p.t_end, p.n_samples)
    V = sampled(mbs, sens_v, p.t_end, p.n_samples, error=RuntimeError)[:, 0]
    A = sampled(mbs, sens_a, p.t_end, p.n_samples, error=RuntimeError)[:, 0]
    P = np.stack([sampled(mbs, k, p.t_end, p.n_samples, error=RuntimeError)[:, :2] for k in sens_pos],
                 axis=1)  # (n_samples, n + 1, 2)
    chord = P[:, -1] - P[:, 0]
    length = np.linalg.norm(chord, axis=1)
    normal = np.stack([-chord[:, 1], chord[:, 0]], axis=1) / length[:, None]
    shape = np.einsum("tkj,tj->tk", P - P[:, :1], normal)
    return Response(t=t, V=V, A=A, D=shape[:, p.n_elements // 2], s=s_nodes, shape=shape, engine="exudyn",
                    seconds=time.perf_counter() - start)
