"""The flexible four-bar in Exudyn: geometrically exact ANCF cables, the independent check of the modal model.

Model: a rigid crank (``NodeRigidBody2D``) pinned to the ground at O2 and turned at the constant rate ω by a
velocity-level coordinate constraint; the coupler and the follower as ``n_elements`` ``ObjectANCFCable2D`` elements
each (EA, EI, ρA of their sections; bending and axial damping β·EI and β·EA, the Kelvin-Voigt damping of
:mod:`.parameters`); revolute joints (pins) between the crank tip and the coupler's first node (B), the coupler's
and the follower's last nodes (C), and the follower's first node and the ground (O4).  The links start straight in
the rigid configuration at θ2 = 0 with the rigid-body velocity field; their axial strain starts at 0 (the
quasi-static one is ~1e-6 and its overdamped axial modes, ζ ≈ 16, settle within a millisecond).  Generalized-α
integration with ``steps_per_sample`` steps between samples and a relative Newton tolerance of 1e-4 (loose, as
flexible links need).  No solution or sensor file is written.

Exudyn would integrate a design that cannot assemble and report success, so each design is checked with
:func:`.kinematics.require_crank_rocker` first, and after the run the pins B, C, O4 and the crank angle are compared
with the closed form (:data:`CLOSURE_TOL`).

Responses: the mid-point paths are the positions of the crank's mid-point (half of B's) and of the links' mid-span
nodes; D3, D4 the mid-span nodes' distances from the chord of their link's end nodes.
"""

from __future__ import annotations

import time

import numpy as np

from mechopt.errors import InputError, MechoptError
from mechopt.sim.exudyn_sampling import add_driven_crank, sampled, solver_settings
from mechopt.sim.flexible_four_bar.kinematics import require_crank_rocker, rigid_motion
from mechopt.sim.flexible_four_bar.parameters import FlexibleFourBar, FlexibleLink
from mechopt.sim.flexible_four_bar.response import FourBarResponse

__all__ = ["CLOSURE_TOL", "simulate_exudyn"]

#: Largest accepted gap at a pin and drift of B from the closed-form crank motion, relative to l2.
CLOSURE_TOL = 1e-4


def simulate_exudyn(p: FlexibleFourBar, steps_per_sample: int = 8, newton_tolerance: float = 1e-4) -> FourBarResponse:
    """Simulate one design with Exudyn's ANCF cable elements.

    Parameters
    ----------
    p : FlexibleFourBar
        The design and settings (SI); ``n_modes`` and ``geometric_stiffness`` do not apply.
    steps_per_sample : int
        Time steps between two output samples.
    newton_tolerance : float
        Relative tolerance of the Newton iterations.

    Returns
    -------
    FourBarResponse

    Raises
    ------
    InfeasibleDesignError
        When the design is not a crank-rocker.
    MechoptError
        When the solved motion leaves a pin open or the crank off its prescribed motion.
    """
    import exudyn as exu  # lazily: importing Exudyn costs ~1 s and only this engine needs it
    import exudyn.itemInterface as items

    if p.n_elements % 2:
        raise InputError(f"n_elements = {p.n_elements}: the Exudyn engine needs an even number (a mid-span node)")
    require_crank_rocker(p.lengths)
    start = time.perf_counter()
    rig0 = rigid_motion(p.lengths, p.omega, np.array([0.0]), p.branch)
    sc = exu.SystemContainer()  # owns the system: it must outlive every call on ``mbs``
    mbs = sc.AddSystem()
    ground = mbs.AddObject(items.ObjectGround())
    n_ground = mbs.AddNode(items.NodePointGround())
    m_ground_coord = mbs.AddMarker(items.MarkerNodeCoordinate(nodeNumber=n_ground, coordinate=0))
    m_crank_tip = add_driven_crank(mbs, items, p.l2, p.omega, ground, m_ground_coord)
    th3, w3, th4, w4 = (float(v[0]) for v in (rig0.theta3, rig0.omega3, rig0.theta4, rig0.omega4))
    coupler = _add_link(mbs, items, p.coupler, p.l3, p.n_elements, p.beta, origin=(p.l2, 0.0),
                        v_origin=(0.0, p.l2 * p.omega), theta=th3, rate=w3)
    follower = _add_link(mbs, items, p.follower, p.l4, p.n_elements, p.beta, origin=(p.l1, 0.0),
                         v_origin=(0.0, 0.0), theta=th4, rate=w4)

    def pin(m0: int, node: int) -> None:
        mbs.AddObject(items.RevoluteJoint2D(markerNumbers=[m0, mbs.AddMarker(items.MarkerNodePosition(
            nodeNumber=node))]))

    pin(m_crank_tip, coupler[0])
    pin(mbs.AddMarker(items.MarkerNodePosition(nodeNumber=coupler[-1])), follower[-1])
    pin(mbs.AddMarker(items.MarkerBodyPosition(bodyNumber=ground, localPosition=[p.l1, 0.0, 0.0])), follower[0])
    out = exu.OutputVariableType
    sensors = [[mbs.AddSensor(items.SensorNode(nodeNumber=k, storeInternal=True, writeToFile=False,
                                               outputVariableType=out.Position)) for k in nodes]
               for nodes in (coupler, follower)]
    mbs.Assemble()
    mbs.SolveDynamic(solver_settings(exu, p.t_end, p.n_samples, steps_per_sample, newton_tolerance))
    P3 = np.stack([sampled(mbs, k, p.t_end, p.n_samples)[:, :2] for k in sensors[0]], axis=1)  # (n_samples, n + 1, 2)
    P4 = np.stack([sampled(mbs, k, p.t_end, p.n_samples)[:, :2] for k in sensors[1]], axis=1)
    _check_closure(p, P3, P4)
    return _response(p, P3, P4, start)


def _add_link(mbs, items, link: FlexibleLink, length: float, n: int, beta: float, origin: tuple[float, float],
              v_origin: tuple[float, float], theta: float, rate: float) -> list[int]:
    """A straight cable link from ``origin`` at the angle ``theta``, moving rigidly; returns its nodes in order.

    The rigid velocity field is v(s) = v_origin + rate · s n and the slope (the unit tangent e) moves at rate · n.
    """
    e = np.array([np.cos(theta), np.sin(theta)])
    nrm = np.array([-e[1], e[0]])
    nodes = []
    for s in np.linspace(0.0, length, n + 1):
        x = np.asarray(origin) + s * e
        v = np.asarray(v_origin) + rate * s * nrm
        nodes.append(mbs.AddNode(items.NodePoint2DSlope1(
            referenceCoordinates=[x[0], x[1], e[0], e[1]],
            initialVelocities=[v[0], v[1], rate * nrm[0], rate * nrm[1]])))
    ea, ei = link.E * link.area, link.bending_stiffness
    for k in range(n):
        mbs.AddObject(items.ObjectANCFCable2D(
            length=length / n, massPerLength=link.mass_per_length, bendingStiffness=ei, axialStiffness=ea,
            bendingDamping=beta * ei, axialDamping=beta * ea, nodeNumbers=[nodes[k], nodes[k + 1]]))
    return nodes


def _check_closure(p: FlexibleFourBar, P3: np.ndarray, P4: np.ndarray) -> None:
    """Pins B, C, O4 closed and B on the prescribed crank circle at the prescribed angle (Exudyn does not check)."""
    t = np.linspace(0.0, p.t_end, p.n_samples)
    B = p.l2 * np.stack([np.cos(p.omega * t), np.sin(p.omega * t)], axis=1)
    gaps = {"B": np.abs(P3[:, 0] - B).max(), "C": np.abs(P3[:, -1] - P4[:, -1]).max(),
            "O4": np.abs(P4[:, 0] - np.array([p.l1, 0.0])).max()}
    worst = max(gaps, key=gaps.get)
    if not gaps[worst] <= CLOSURE_TOL * p.l2:
        raise MechoptError(f"Exudyn run of the flexible four-bar left pin {worst} {gaps[worst] * 1e3:.3g} mm off "
                           f"(tolerance {CLOSURE_TOL * p.l2 * 1e3:.3g} mm)")


def _deflection(P: np.ndarray) -> np.ndarray:
    """Each node's distance from the chord of the end nodes, along the chord's +90° normal (n_samples, n + 1)."""
    chord = P[:, -1] - P[:, 0]
    normal = np.stack([-chord[:, 1], chord[:, 0]], axis=1) / np.linalg.norm(chord, axis=1)[:, None]
    return np.einsum("tkj,tj->tk", P - P[:, :1], normal)


def _response(p: FlexibleFourBar, P3: np.ndarray, P4: np.ndarray, start: float) -> FourBarResponse:
    """The four-bar's responses from the sampled node positions of both links."""
    mid = p.n_elements // 2
    shape3, shape4 = _deflection(P3), _deflection(P4)
    s = np.linspace(0.0, 1.0, p.n_elements + 1)
    return FourBarResponse(t=np.linspace(0.0, p.t_end, p.n_samples), crank=0.5 * P3[:, 0], coupler=P3[:, mid],
                           follower=P4[:, mid], D3=shape3[:, mid], D4=shape4[:, mid], s3=s * p.l3, s4=s * p.l4,
                           shape3=shape3, shape4=shape4, engine="exudyn", seconds=time.perf_counter() - start)
