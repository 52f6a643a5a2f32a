"""The paper's linear kineto-elasto-dynamic (KED) model of the flexible connecting rod, in modal coordinates.

The rod's elastic deflection w(s, t), measured from the rigid rod in the frame that moves with it, obeys the
paper's Eq. 9, M ẅ + C ẇ + K w = −M ü_r: the rigid-body acceleration field of the rod (linear in s: A's transverse
acceleration plus φ̈ s) loads the beam, and, as in the paper (Eq. 3), the normal, Coriolis and tangential terms of
the elastic motion are dropped (they are of order φ̇²/ω1² ≈ 1e-3 here).  The rod is pinned at A and B; Hermite
beam elements (:mod:`.beam`), the lowest ``n_modes`` bending modes (Eqs. 13-16), material damping C = β K, i.e.
ζ_k = β ω_k / 2, and a fixed-step RK4 integration from the undeformed, co-moving state at t = 0.

The slider's V and A are the rigid-body kinematics, as the paper's Table 5 shows (exact zeros for designs of other
material but the same lengths).  Option ``axial_stiffening`` adds the geometric stiffness of the rod's quasi-static
axial force (slider and rod inertia; tension stiffens, compression softens), a time-varying coupling of the modes
the paper's model does not have; the geometrically exact Exudyn cable includes it, so it is the like-for-like
comparison with that engine.
"""

from __future__ import annotations

import math
import time

import numpy as np
from numba import njit
from scipy.linalg import eigh

from mechopt.sim.flexible_slider_crank.beam import rod_matrices
from mechopt.sim.flexible_slider_crank.kinematics import rigid_motion, rigid_state
from mechopt.sim.flexible_slider_crank.parameters import FlexibleSliderCrank
from mechopt.sim.flexible_slider_crank.response import Response

__all__ = ["natural_frequencies", "simulate_modal"]

#: RK4 step: |λ| dt at most this for the fastest kept mode (RK4's stability limit is 2.78; 0.5 keeps mode 1's
#: phase error far below the engines' agreement).
_LAMBDA_DT = 0.5


def natural_frequencies(p: FlexibleSliderCrank) -> np.ndarray:
    """Bending natural circular frequencies of the pinned-pinned rod, lowest ``n_modes`` (rad/s)."""
    rm = rod_matrices(p.l3, p.n_elements, p.rho * p.area, p.E * p.second_moment)
    return np.sqrt(eigh(rm.K, rm.M, eigvals_only=True)[: p.n_modes])


@njit(cache=True)
def _accel(lam, beta, load, coef, geo, e, v, out):
    """η̈ = f − β Λ η̇ − Λ η − Σ_p c_p G_p η into ``out``; f = −(a_A⊥ load[0] + φ̈ load[1])."""
    nm = lam.shape[0]
    for m in range(nm):
        out[m] = -(coef[3] * load[0, m] + coef[4] * load[1, m]) - beta * lam[m] * v[m] - lam[m] * e[m]
    for p in range(3):
        c = coef[p]
        if c != 0.0:
            for m in range(nm):
                acc = 0.0
                for n in range(nm):
                    acc += geo[p, m, n] * e[n]
                out[m] -= c * acc


@njit(cache=True)
def _drive(r, l, omega, t, rho_a, slider_mass, stiffening, coef):
    """Loads of the instant t into ``coef``: tension coefficients c0, c1, c2 (or 0), a_A⊥, φ̈."""
    _, _, _, acc, phi, phi_d, phi_dd, a_par, a_perp = rigid_state(r, l, omega, t)
    if stiffening:
        # slider inertia at B (T_B = −m a_B / cos φ, the rod's small shear at B neglected) plus the rod's own
        # axial inertia ρA (a_A∥ − φ̇² s) integrated from s to the end
        t_b = -slider_mass * acc / math.cos(phi)
        coef[0] = t_b - rho_a * a_par * l + 0.5 * rho_a * phi_d**2 * l * l
        coef[1] = rho_a * a_par
        coef[2] = -0.5 * rho_a * phi_d**2
    else:
        coef[0] = coef[1] = coef[2] = 0.0
    coef[3] = a_perp
    coef[4] = phi_dd


@njit(cache=True)
def _integrate(lam, beta, load, geo, r, l, omega, rho_a, slider_mass, stiffening, n_sub, dt, n_out):
    """Classical RK4 from rest (η = η̇ = 0 at t = 0); η at every ``n_sub``-th step."""
    nm = lam.shape[0]
    out = np.zeros((n_out, nm))
    eta = np.zeros(nm)
    vel = np.zeros(nm)
    ka = np.zeros((4, nm))
    kx = np.zeros((4, nm))
    e = np.zeros(nm)
    v = np.zeros(nm)
    c_start = np.zeros(5)
    c_mid = np.zeros(5)
    c_end = np.zeros(5)
    _drive(r, l, omega, 0.0, rho_a, slider_mass, stiffening, c_end)
    for j in range((n_out - 1) * n_sub):
        t0 = j * dt
        c_start[:] = c_end
        _drive(r, l, omega, t0 + 0.5 * dt, rho_a, slider_mass, stiffening, c_mid)
        _drive(r, l, omega, t0 + dt, rho_a, slider_mass, stiffening, c_end)
        for m in range(nm):
            kx[0, m] = vel[m]
        _accel(lam, beta, load, c_start, geo, eta, vel, ka[0])
        for stage in range(3):
            w = dt if stage == 2 else 0.5 * dt
            for m in range(nm):
                e[m] = eta[m] + w * kx[stage, m]
                v[m] = vel[m] + w * ka[stage, m]
                kx[stage + 1, m] = v[m]
            _accel(lam, beta, load, c_end if stage == 2 else c_mid, geo, e, v, ka[stage + 1])
        for m in range(nm):
            eta[m] += dt / 6.0 * (kx[0, m] + 2.0 * kx[1, m] + 2.0 * kx[2, m] + kx[3, m])
            vel[m] += dt / 6.0 * (ka[0, m] + 2.0 * ka[1, m] + 2.0 * ka[2, m] + ka[3, m])
        if (j + 1) % n_sub == 0:
            out[(j + 1) // n_sub] = eta
    return out


def simulate_modal(p: FlexibleSliderCrank, n_shape_points: int = 41) -> Response:
    """Simulate one design with the modal KED model.

    Parameters
    ----------
    p : FlexibleSliderCrank
        The design and settings (SI).
    n_shape_points : int
        Points along the rod at which the deflected shape is returned.

    Returns
    -------
    Response
        V, A rigid-body kinematics; D and the shape from the elastic modes.
    """
    start = time.perf_counter()
    rm = rod_matrices(p.l3, p.n_elements, p.rho * p.area, p.E * p.second_moment)
    w2, phi = eigh(rm.K, rm.M)  # mass-normalised modes
    lam = np.ascontiguousarray(w2[: p.n_modes])
    phi = np.ascontiguousarray(phi[:, : p.n_modes])
    geo = np.ascontiguousarray(np.einsum("im,pij,jn->pmn", phi, rm.geo, phi))

    t = np.linspace(0.0, p.t_end, p.n_samples)
    dt_out = t[1] - t[0]
    omega_max = math.sqrt(lam[-1])
    if p.axial_stiffening:  # the axial force shifts the modes; a margin of 2 covers up to half the Euler load
        omega_max *= 2.0
    fastest = max(omega_max, p.beta * omega_max**2)
    n_sub = max(1, math.ceil(dt_out * fastest / _LAMBDA_DT))
    dt = dt_out / n_sub
    rho_a = p.rho * p.area
    load = np.ascontiguousarray(rho_a * (rm.load @ phi))  # ∫ ρA s^p Nᵀ ds on the modes
    eta = _integrate(lam, float(p.beta), load, geo, float(p.l2), float(p.l3), float(p.omega), rho_a,
                     float(p.slider_mass), bool(p.axial_stiffening), n_sub, dt, p.n_samples)
    q = eta @ phi.T
    mid = rm.shape_at(np.array([0.5 * p.l3]))[0]
    s = np.linspace(0.0, p.l3, n_shape_points)
    shape = q @ rm.shape_at(s).T
    rigid = rigid_motion(p.l2, p.l3, p.omega, t)
    return Response(t=t, V=rigid.v, A=rigid.acc, D=q @ mid, s=s, shape=shape, engine="modal",
                    seconds=time.perf_counter() - start)
