"""Analytic inverse dynamics of the four-bar in its rocker coordinate ψ (Lagrange), the independent check of pymunk.

With ψ as the generalised coordinate the kinetic energy is E = ½ m(ψ) ψ̇², m being the reduced inertia of all
bodies, and the virtual work of the motor torque τ (on θ) and of the static rocker load M_r (on ψ) gives

    τ θ'(ψ) = m(ψ) ψ̈ + ½ m'(ψ) ψ̇² + M_r(ψ),

so τ = (m ψ̈ + ½ m' ψ̇² + M_r) / θ'.  Nothing divides by ψ̇, so the stroke ends (ψ̇ = 0) are exact.

m(ψ) = J0 θ'² + I_r + m_c |v_G/ψ̇|² + (m_c |AB|²/12) φ'²   (crank+motor, rocker+beam, coupler as a uniform bar
with centre G and angle φ); m' uses θ'' from the exact kinematics.  SI units inside (m, kg, s, N·m); the public
functions take designs in mm and convert here, in one place.
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit, prange

from mechopt.sim.four_bar.feasibility import as_designs, check_feasibility, require_movable
from mechopt.sim.four_bar.kinematics import _crank_kernel, check_design, crank_angle
from mechopt.sim.four_bar.load import _load_at
from mechopt.sim.four_bar.mechanism import FourBar
from mechopt.sim.four_bar.result import SimulationResult, rms_over_cycle

MM = 1e-3  # m per mm: the single place where the user's mm become the dynamics' metres

#: Default number of time intervals over one cycle for the analytic engine.
N_INTERVALS = 800


@njit(cache=True)
def _torque_kernel(oa, ab, bc, xc, yc, branch, j0, ir, mc, c, s, psid, psidd, load):
    """Motor torque (N·m) at one instant, given c = cos ψ and s = sin ψ; lengths in m.  NaN where the loop is open."""
    ok, ax, ay, t1, t2 = _crank_kernel(oa, ab, bc, xc, yc, c, s, branch)
    if not ok:
        return np.nan
    m = j0 * t1 * t1 + ir
    dm = 2.0 * j0 * t1 * t2
    if mc > 0.0:
        rx = bc * c  # B − C
        ry = bc * s
        ex = xc + rx - ax  # e = B − A, |e| = |AB|
        ey = yc + ry - ay
        # Derivatives with respect to ψ: A' = A_θ θ', A_θ = (−a_y, a_x), A_θθ = −A; B' = (−r_y, r_x), B'' = −r.
        gx = 0.5 * (-ay * t1 - ry)  # v_G / ψ̇, G the coupler's middle
        gy = 0.5 * (ax * t1 + rx)
        gpx = 0.5 * (-ax * t1 * t1 - ay * t2 - rx)
        gpy = 0.5 * (-ay * t1 * t1 + ax * t2 - ry)
        epx = -ry + ay * t1
        epy = rx - ax * t1
        eppx = -rx + ax * t1 * t1 + ay * t2
        eppy = -ry + ay * t1 * t1 - ax * t2
        ab2 = ab * ab
        ph1 = (ex * epy - ey * epx) / ab2
        ph2 = (ex * eppy - ey * eppx) / ab2
        ic = mc * ab2 / 12.0
        m += mc * (gx * gx + gy * gy) + ic * ph1 * ph1
        dm += 2.0 * mc * (gx * gpx + gy * gpy) + 2.0 * ic * ph1 * ph2
    return (m * psidd + 0.5 * dm * psid * psid + load) / t1


@njit(cache=True)
def _curve(oa, ab, bc, xc, yc, branch, j0, ir, mc, psi, psid, psidd, load, tau):
    for k in range(psi.size):
        tau[k] = _torque_kernel(
            oa, ab, bc, xc, yc, branch, j0, ir, mc, np.cos(psi[k]), np.sin(psi[k]), psid[k], psidd[k], load[k]
        )


@njit(cache=True)
def _design_rms_peak(designs_m, i, xc, yc, branch, j0, ir, mc, cpsi, spsi, psid, psidd, load, weights, period, out):
    oa = designs_m[i, 0]
    ab = designs_m[i, 1]
    bc = designs_m[i, 2]
    acc = 0.0
    peak = 0.0
    for k in range(cpsi.size):
        tau = _torque_kernel(oa, ab, bc, xc, yc, branch, j0, ir, mc, cpsi[k], spsi[k], psid[k], psidd[k], load[k])
        acc += weights[k] * tau * tau
        a = abs(tau)
        if a > peak or np.isnan(a):
            peak = a
    out[i, 0] = np.sqrt(acc / period)
    out[i, 1] = peak


@njit(cache=True, parallel=True)
def _batch(designs_m, xc, yc, branch, j0, ir, mc, cpsi, spsi, psid, psidd, load, weights, period, out):
    """T_RMS and T_max of many designs on one shared time grid (trapezoid weights), parallel over designs."""
    for i in prange(designs_m.shape[0]):
        _design_rms_peak(designs_m, i, xc, yc, branch, j0, ir, mc, cpsi, spsi, psid, psidd, load, weights, period, out)


@njit(cache=True)
def _batch_few(designs_m, xc, yc, branch, j0, ir, mc, cpsi, spsi, psid, psidd, load, weights, period, out):
    """:func:`_batch` on one thread."""
    for i in range(designs_m.shape[0]):
        _design_rms_peak(designs_m, i, xc, yc, branch, j0, ir, mc, cpsi, spsi, psid, psidd, load, weights, period, out)


#: Below this many designs the batch runs on one thread: waking numba's thread pool costs milliseconds on a busy
#: machine, more than a few designs' work.
_PARALLEL_FROM = 256


def _load_on_grid(mechanism: FourBar, psi: np.ndarray) -> np.ndarray:
    return np.array([_load_at(mechanism.load.breaks, mechanism.load.coefs, p) for p in psi])


def torque_curve(design: np.ndarray, mechanism: FourBar, t: np.ndarray) -> np.ndarray:
    """Signed motor torque τ(t) of one design from the analytic model.

    Parameters
    ----------
    design : (3,) array_like
        |OA|, |AB|, |BC| in mm.
    mechanism : FourBar
        The fixed part of the mechanism.
    t : (n,) array_like
        Times (s).

    Returns
    -------
    (n,) ndarray
        τ in N·m, positive in the sense of increasing θ; NaN where the design cannot be assembled.
    """
    oa, ab, bc = check_design(design) * MM
    t = np.asarray(t, dtype=float)
    psi, psid, psidd = mechanism.motion(t)
    load = _load_on_grid(mechanism, psi.ravel())
    tau = np.empty(psi.size)
    xc, yc = (v * MM for v in mechanism.pivot_c)
    _curve(
        oa, ab, bc, xc, yc, mechanism.branch, mechanism.j0, mechanism.i_r, mechanism.coupler_mass,
        psi.ravel(), psid.ravel(), psidd.ravel(), load, tau,
    )
    return tau.reshape(t.shape)


def simulate_analytic(
    design: np.ndarray, mechanism: FourBar, n_intervals: int = N_INTERVALS
) -> SimulationResult:
    """Motor torque over one cycle from the analytic inverse dynamics.

    Parameters
    ----------
    design : (3,) array_like
        |OA|, |AB|, |BC| in mm.
    mechanism : FourBar
        The fixed part of the mechanism.
    n_intervals : int
        Uniform time intervals over the cycle.

    Returns
    -------
    SimulationResult
        Torque curve, T_RMS and T_max (N·m), margins.

    Raises
    ------
    InfeasibleDesignError
        If the design cannot be driven through the stroke.
    """
    start = time.perf_counter()
    design = check_design(design)
    report = require_movable(design, mechanism)
    t = mechanism.motion.time_grid(n_intervals)
    tau = torque_curve(design, mechanism, t)
    psi, _, _ = mechanism.motion(t)
    theta = np.unwrap(crank_angle(design, mechanism.pivot_c, psi, mechanism.branch)[0])
    return SimulationResult(
        design=design, engine="analytic", t=t, tau=tau, theta=theta, psi=psi,
        t_rms=rms_over_cycle(t, tau), t_max=float(np.max(np.abs(tau))),
        margins=report.margins(0), feasible=bool(report.feasible[0]), message=report.message(0),
        dt=float(t[1] - t[0]), wall_time_s=time.perf_counter() - start,
    )


def analytic_batch(
    designs: np.ndarray, mechanism: FourBar, n_intervals: int = N_INTERVALS, check: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """T_RMS and T_max of many designs at once (numba, parallel over designs).

    Parameters
    ----------
    designs : (n, 3) array_like
        |OA|, |AB|, |BC| in mm.
    mechanism : FourBar
        The fixed part of the mechanism.
    n_intervals : int
        Uniform time intervals over the cycle.
    check : bool
        If True, designs that cannot be driven through the stroke get NaN (the feasibility check costs about as
        much as the torque); if False the caller guarantees movability.

    Returns
    -------
    t_rms, t_max : (n,) ndarray
        N·m; NaN for designs that cannot move through the stroke.
    """
    arr = as_designs(designs)
    t = mechanism.motion.time_grid(n_intervals)
    psi, psid, psidd = mechanism.motion(t)
    load = _load_on_grid(mechanism, psi)
    weights = np.full(t.size, t[1] - t[0])
    weights[[0, -1]] *= 0.5
    out = np.empty((arr.shape[0], 2))
    xc, yc = (v * MM for v in mechanism.pivot_c)
    kernel = _batch if arr.shape[0] >= _PARALLEL_FROM else _batch_few
    kernel(
        np.ascontiguousarray(arr * MM), xc, yc, mechanism.branch, mechanism.j0, mechanism.i_r,
        mechanism.coupler_mass, np.cos(psi), np.sin(psi), psid, psidd, load, weights, float(t[-1] - t[0]), out,
    )
    if check:
        bad = ~check_feasibility(arr, mechanism).movable
        out[bad] = np.nan
    return out[:, 0], out[:, 1]
