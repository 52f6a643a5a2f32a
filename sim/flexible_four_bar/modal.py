"""The paper's linear kineto-elasto-dynamic (KED) model of the flexible four-bar, in modal coordinates (numba).

Each flexible link (coupler B-C, follower O4-C) bends about its rigid chord, w(s, t), and obeys the paper's Eq. 9,
M ẅ + C ẇ + K w = −M ü_r: the link's rigid-body transverse acceleration field a⊥0 + α s (:mod:`.loads`) loads a
pinned-pinned Euler-Bernoulli beam (Hermite elements of :mod:`mechopt.sim.flexible_slider_crank.beam`).
As in the paper (Eq. 3)
the normal, Coriolis and tangential terms of the elastic motion are dropped (order ω3²/ω1² ≈ 1e-3).  The joints are
pinned and the elastic displacement of C is neglected: it is axial strain, EI/(EA l²) ≈ 1e-5 of the bending.  So the
two links bend independently; each keeps its lowest ``n_modes`` modes (Eqs. 13-16), material damping C = β K
(ζ_k = β ω_k / 2) and is integrated with fixed-step RK4 from the straight, co-moving state at t = 0.

Option ``geometric_stiffness`` adds what the linear model lacks and Exudyn's geometrically exact cable has: the
geometric stiffness of each link's axial force N(s) (:mod:`.loads`; a time-varying coupling of the modes), its c0
shifted by both links' moments of inertia ∫ ρA s (Δα s + ẅ) ds (they change the pin force at C), the centrifugal
softening −ρA ω² w of the rotating chord frame (the normal term of Eq. 1), and the turn of both chords as the
links' bending shortens them: a chord is δ = ½ ∫ w'² ds shorter than its link, and the loop
B + (l3 − δ3) e3 = O4 + (l4 − δ4) e4 then gives both links the extra angular accelerations Δα3, Δα4 of
l3 Δα3 n3 − l4 Δα4 n4 = δ̈3 e3 − δ̈4 e4, each loading its link with −ρA Δα s.  δ is second order in w, but in the
start transient the coupler rings at millimetres and δ̈3 ≈ ω1² δ3 shakes the follower, whose own deflection is a
tenth of the coupler's.  The shift of c0 and δ̈ are taken from the full η̈ they change: near the Euler load the
geometric term is a large share of Λ η, and the linear η̈ alone would be a spurious acceleration.  Without the
chords' turn the engines part by 0.6 % of D4's range (Eq. 18) below a tenth of the Euler load, with a linear η̈ by
11 % at 0.28; with both 0.15 % and 0.55 % (tests/sim/flexible_four_bar/test_four_bar_engines.py, README).
Both links share one RK4 step, set by the stiffer.  The mid-point paths are the rigid mid-points moved by the
mid-span deflection along the chord's normal.
"""

from __future__ import annotations

import math
import time

import numpy as np
from numba import njit
from scipy.linalg import eigh

from mechopt.sim.flexible_four_bar.kinematics import require_crank_rocker, rigid_motion
from mechopt.sim.flexible_four_bar.loads import drive_tables
from mechopt.sim.flexible_four_bar.parameters import FlexibleFourBar, FlexibleLink
from mechopt.sim.flexible_four_bar.response import FourBarResponse
from mechopt.sim.flexible_slider_crank.beam import rod_matrices

__all__ = ["link_frequencies", "simulate_modal"]

#: RK4 step: |λ| dt at most this for the fastest kept mode (RK4's stability limit is 2.78; 0.5 keeps mode 1's phase
#: error far below the engines' agreement).
_LAMBDA_DT = 0.5


def link_frequencies(link: FlexibleLink, length: float, n_elements: int, n_modes: int) -> np.ndarray:
    """Bending natural circular frequencies of a pinned-pinned link, lowest ``n_modes`` (rad/s)."""
    rm = rod_matrices(length, n_elements, link.mass_per_length, link.bending_stiffness)
    return np.sqrt(eigh(rm.K, rm.M, eigvals_only=True)[:n_modes])


@njit(cache=True)
def _accel(lam, beta, load, geo, inertia, row3, row4, geometric, e, v, g, out):
    """η̈ of both links (arrays (2, n_modes)) into ``out``; ``g`` is scratch of the same shape.

    Linear part η̈ = f − β Λ η̇ − Λ η with f = −(a⊥0 load[0] + α load[1]); with ``geometric``, the terms of
    :func:`_geometric` (M-orthonormal modes; ``inertia`` holds each link's ∫ ρA s² ds about its first joint).
    """
    nm = lam.shape[1]
    for k in range(2):
        row = row3 if k == 0 else row4
        for m in range(nm):
            out[k, m] = -(row[3] * load[k, 0, m] + row[4] * load[k, 1, m]) - beta * lam[k, m] * v[k, m] \
                - lam[k, m] * e[k, m]
    if geometric:
        _geometric(load, geo, inertia, row3, row4, e, v, g, out)


@njit(cache=True)
def _geometric(load, geo, inertia, row3, row4, e, v, g, out):
    """Add to the linear η̈ in ``out``: the centrifugal softening ω² η, minus the geometric stiffness
    (c0 + Δc0) G0 η + c1 G1 η + c2 G2 η, minus the load Δα load[1] of the chords' turn as they shorten (module
    docstring).

    Δc0 follows from each link's moment of inertia ∫ ρA s (Δα s + ẅ) ds (columns k_self, k_other) and Δα from the
    chords' δ̈ = η̇ᵀ G0 η̇ + ηᵀ G0 η̈ (the same columns invert the loop's 2 × 2 system); both are taken from the η̈
    they change (a small linear system, solved by fixed-point iteration): near the Euler load the geometric term
    is a large part of Λ η, and the linear η̈ alone would put a spurious inertia into Δc0.  The Coriolis term
    2 δ̇ ω / l of the shortening chord is left out: the material points' own axial drift u̇ ≈ −δ̇ s / l gives the
    opposite load 2 ω u̇, and adding the one without the other moved the worst design away from Exudyn (measured).
    """
    nm = out.shape[1]
    sums = np.zeros((2, 6))  # p = Σ L1 a, q = Σ L1 g, r = Σ L1², u = η̇ᵀG0η̇ + Σ g a, w = Σ g², x = Σ g L1
    for k in range(2):
        row = row3 if k == 0 else row4
        for m in range(nm):
            acc = row[5] * row[5] * e[k, m]
            g[k, m] = 0.0
            for n in range(nm):
                acc -= (row[0] * geo[k, 0, m, n] + row[1] * geo[k, 1, m, n] + row[2] * geo[k, 2, m, n]) * e[k, n]
                g[k, m] += geo[k, 0, m, n] * e[k, n]
                sums[k, 3] += geo[k, 0, m, n] * v[k, m] * v[k, n]
            out[k, m] += acc
        for m in range(nm):
            l1 = load[k, 1, m]
            sums[k, 0] += l1 * out[k, m]
            sums[k, 1] += l1 * g[k, m]
            sums[k, 2] += l1 * l1
            sums[k, 3] += g[k, m] * out[k, m]
            sums[k, 4] += g[k, m] * g[k, m]
            sums[k, 5] += g[k, m] * l1
    shift3 = shift4 = da3 = da4 = 0.0
    for _ in range(8):
        s3 = sums[0, 0] - shift3 * sums[0, 1] + da3 * (inertia[0] - sums[0, 2])  # ∫ ρA s (Δα s + ẅ) ds
        s4 = sums[1, 0] - shift4 * sums[1, 1] + da4 * (inertia[1] - sums[1, 2])
        dd3 = sums[0, 3] - shift3 * sums[0, 4] - da3 * sums[0, 5]
        dd4 = sums[1, 3] - shift4 * sums[1, 4] - da4 * sums[1, 5]
        shift3 = row3[6] * s3 + row3[7] * s4
        shift4 = row4[6] * s4 + row4[7] * s3
        da3 = row3[6] * dd3 + row4[7] * dd4
        da4 = row3[7] * dd3 + row4[6] * dd4
    for m in range(nm):
        out[0, m] -= shift3 * g[0, m] + da3 * load[0, 1, m]
        out[1, m] -= shift4 * g[1, m] + da4 * load[1, 1, m]


@njit(cache=True)
def _integrate(lam, beta, load, geo, inertia, drive3, drive4, geometric, n_sub, dt, n_out):
    """Classical RK4 of both links from rest; ``drive3``, ``drive4`` hold the rows at every half step.

    Returns η (n_out, 2, n_modes) at every ``n_sub``-th step.
    """
    nm = lam.shape[1]
    out = np.zeros((n_out, 2, nm))
    eta = np.zeros((2, nm))
    vel = np.zeros((2, nm))
    ka = np.zeros((4, 2, nm))
    kx = np.zeros((4, 2, nm))
    e = np.zeros((2, nm))
    v = np.zeros((2, nm))
    g = np.zeros((2, nm))
    for j in range((n_out - 1) * n_sub):
        kx[0] = vel
        _accel(lam, beta, load, geo, inertia, drive3[2 * j], drive4[2 * j], geometric, eta, vel, g, ka[0])
        for stage in range(3):
            w = dt if stage == 2 else 0.5 * dt
            for k in range(2):  # explicit loops: array expressions would allocate at every stage
                for m in range(nm):
                    e[k, m] = eta[k, m] + w * kx[stage, k, m]
                    v[k, m] = vel[k, m] + w * ka[stage, k, m]
                    kx[stage + 1, k, m] = v[k, m]
            h = 2 * j + (2 if stage == 2 else 1)
            _accel(lam, beta, load, geo, inertia, drive3[h], drive4[h], geometric, e, v, g, ka[stage + 1])
        for k in range(2):
            for m in range(nm):
                eta[k, m] += dt / 6.0 * (kx[0, k, m] + 2.0 * kx[1, k, m] + 2.0 * kx[2, k, m] + kx[3, k, m])
                vel[k, m] += dt / 6.0 * (ka[0, k, m] + 2.0 * ka[1, k, m] + 2.0 * ka[2, k, m] + ka[3, k, m])
        if (j + 1) % n_sub == 0:
            out[(j + 1) // n_sub] = eta
    return out


def _modes(p: FlexibleFourBar, k: int):
    """Matrices of link ``k`` (3 or 4) and its lowest modes: (rod matrices, Λ, Φ, modal load, modal geometric)."""
    link = p.coupler if k == 3 else p.follower
    rm = rod_matrices(p.l3 if k == 3 else p.l4, p.n_elements, link.mass_per_length, link.bending_stiffness)
    w2, phi = eigh(rm.K, rm.M)  # mass-normalised modes
    phi = phi[:, : p.n_modes]
    geo = np.einsum("im,pij,jn->pmn", phi, rm.geo, phi)
    return rm, w2[: p.n_modes], phi, link.mass_per_length * (rm.load @ phi), geo  # load: ∫ ρA s^p Nᵀ ds Φ


def _bend(p: FlexibleFourBar, t: np.ndarray, s3: np.ndarray, s4: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Deflection of each link at its mid-span and at the arc lengths ``s3``, ``s4``, at the sample times ``t``."""
    modes = [_modes(p, 3), _modes(p, 4)]
    lam = np.ascontiguousarray(np.stack([m[1] for m in modes]))
    omega_max = math.sqrt(lam.max())
    if p.geometric_stiffness:  # the axial force shifts the modes; a margin of 2 covers up to half the Euler load
        omega_max *= 2.0
    dt_out = t[1] - t[0]
    n_sub = max(1, math.ceil(dt_out * max(omega_max, p.beta * omega_max**2) / _LAMBDA_DT))
    dt = dt_out / n_sub
    halves = np.arange(2 * (p.n_samples - 1) * n_sub + 1) * (0.5 * dt)
    masses = (p.coupler.mass_per_length * p.l3, p.follower.mass_per_length * p.l4)
    drives = drive_tables(p.lengths, p.omega, p.branch, masses, halves)
    inertia = np.array([masses[0] * p.l3**2 / 3.0, masses[1] * p.l4**2 / 3.0])  # ∫ ρA s² ds
    eta = _integrate(lam, float(p.beta), np.ascontiguousarray(np.stack([m[3] for m in modes])),
                     np.ascontiguousarray(np.stack([m[4] for m in modes])), inertia, drives[0], drives[1],
                     bool(p.geometric_stiffness), n_sub, dt, p.n_samples)
    out = []
    for k, (rm, _, phi, _, _) in enumerate(modes):
        q = eta[:, k] @ phi.T
        out.append((q @ rm.shape_at(np.array([0.5 * rm.length]))[0], q @ rm.shape_at((s3, s4)[k]).T))
    return out


def simulate_modal(p: FlexibleFourBar, n_shape_points: int = 41) -> FourBarResponse:
    """Simulate one design with the modal KED model.

    Parameters
    ----------
    p : FlexibleFourBar
        The design and settings (SI).
    n_shape_points : int
        Points along each link at which its deflected shape is returned.

    Returns
    -------
    FourBarResponse

    Raises
    ------
    InfeasibleDesignError
        When the design is not a crank-rocker (the loop cannot close over a whole turn).
    """
    start = time.perf_counter()
    require_crank_rocker(p.lengths)
    t = np.linspace(0.0, p.t_end, p.n_samples)
    rig = rigid_motion(p.lengths, p.omega, t, p.branch)
    s3, s4 = np.linspace(0.0, p.l3, n_shape_points), np.linspace(0.0, p.l4, n_shape_points)
    (D3, shape3), (D4, shape4) = _bend(p, t, s3, s4)

    def unit(th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        e = np.stack([np.cos(th), np.sin(th)], axis=1)
        return e, np.stack([-e[:, 1], e[:, 0]], axis=1)

    e3, n3 = unit(rig.theta3)
    e4, n4 = unit(rig.theta4)
    o4 = np.array([p.l1, 0.0])
    return FourBarResponse(
        t=t, crank=0.5 * rig.B, coupler=rig.B + 0.5 * p.l3 * e3 + D3[:, None] * n3,
        follower=o4 + 0.5 * p.l4 * e4 + D4[:, None] * n4, D3=D3, D4=D4, s3=s3, s4=s4, shape3=shape3,
        shape4=shape4, engine="modal", seconds=time.perf_counter() - start)
