"""Analytic inverse dynamics of the slider-crank in its crank coordinate θ (Lagrange), the check of pymunk.

With θ as the generalised coordinate the kinetic energy is E = ½ M(θ) θ̇² and the virtual work of the motor torque
τ, of the force F_s on the slider (spring and external force) and of gravity on the rod gives

    τ = M(θ) θ̈ + ½ M'(θ) θ̇² − F_s x'(θ) + m_3 g y_G'(θ),

    M(θ) = J0 + m_3 |G'(θ)|² + I_3 φ'(θ)² + m_4 x'(θ)²,

G = A + c (B − A) being the rod's centre of mass (c = ``rod_com``), φ the rod angle and x the slider position, all
with their exact θ-derivatives from :mod:`.kinematics`; M' uses the second derivatives.  F_s = −k (x − x_free) + F.
SI inside (m, kg, s, N, N·m); the public functions take designs in mm and convert here, in one place.
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit

from mechopt.sim.slider_crank.feasibility import COLUMNS, require_assemblable
from mechopt.sim.slider_crank.kinematics import _slider_kernel, check_design, slider_position
from mechopt.sim.slider_crank.mechanism import SliderCrank
from mechopt.sim.slider_crank.result import SliderCrankResult

MM = 1e-3  # m per mm: the single place where the user's mm become the dynamics' metres

#: Default number of time intervals over one revolution.
N_INTERVALS = 720


@njit(cache=True)
def _torque_kernel(r, l, h, branch, j0, m3, i3, cg, m4, k, x_free, force, g, theta, thd, thdd):
    """Motor torque (N·m) at one instant; lengths in m, k in N/m.  NaN where the loop is open."""
    c = np.cos(theta)
    s = np.sin(theta)
    ok, x, x1, x2, phi, phi1, phi2 = _slider_kernel(r, l, h, c, s, branch)
    if not ok:
        return np.nan
    ax = r * c
    ay = r * s
    # G' = (1 − c_g) A' + c_g B', A' = (−a_y, a_x), B' = (x', 0); G'' likewise with A'' = −A, B'' = (x'', 0).
    gx1 = (1.0 - cg) * (-ay) + cg * x1
    gy1 = (1.0 - cg) * ax
    gx2 = (1.0 - cg) * (-ax) + cg * x2
    gy2 = (1.0 - cg) * (-ay)
    m = j0 + m3 * (gx1 * gx1 + gy1 * gy1) + i3 * phi1 * phi1 + m4 * x1 * x1
    dm = 2.0 * m3 * (gx1 * gx2 + gy1 * gy2) + 2.0 * i3 * phi1 * phi2 + 2.0 * m4 * x1 * x2
    fs = -k * (x - x_free) + force
    return m * thdd + 0.5 * dm * thd * thd - fs * x1 + m3 * g * gy1


@njit(cache=True)
def _curve(r, l, h, branch, j0, m3, i3, cg, m4, k, x_free, force, g, theta, thd, thdd, tau):
    for i in range(theta.size):
        tau[i] = _torque_kernel(r, l, h, branch, j0, m3, i3, cg, m4, k, x_free, force, g, theta[i], thd[i], thdd[i])


def si_parameters(design: np.ndarray, mechanism: SliderCrank) -> tuple:
    """The kernel's parameters in SI: (r, l, h, branch, j0, m3, i3, c_g, m4, k, x_free, F, g)."""
    r, l, h = check_design(design) * MM
    mc = mechanism
    return (r, l, h, mc.branch, mc.j0, mc.rod_mass, mc.rod_inertia_si(l), mc.rod_com, mc.slider_mass,
            mc.spring_k / MM, mc.spring_free_mm * MM, mc.force, mc.gravity)


def torque_curve(design: np.ndarray, mechanism: SliderCrank, t: np.ndarray) -> np.ndarray:
    """Signed motor torque τ(t) (N·m, positive along increasing θ) of one design at times ``t`` (s).

    Parameters
    ----------
    design : (3,) array_like
        r, l, h in mm.
    mechanism : SliderCrank
        The fixed part of the mechanism.
    t : array_like
        Times (s).

    Returns
    -------
    ndarray
        τ (N·m), shape of ``t``; NaN where the loop cannot close.
    """
    t = np.asarray(t, dtype=float)
    theta, thd, thdd = mechanism.motion(t.ravel())
    tau = np.empty(theta.size)
    _curve(*si_parameters(design, mechanism), theta, thd, thdd, tau)
    return tau.reshape(t.shape)


def rms_over_cycle(t: np.ndarray, tau: np.ndarray) -> float:
    """sqrt of the time average of τ² over the cycle, trapezoid rule on the time grid (N·m)."""
    return float(np.sqrt(np.trapezoid(tau * tau, t) / (t[-1] - t[0])))


def simulate_analytic(design: np.ndarray, mechanism: SliderCrank, n_intervals: int = N_INTERVALS
                      ) -> SliderCrankResult:
    """Motor torque over one revolution from the analytic inverse dynamics.

    Parameters
    ----------
    design : (3,) array_like
        r, l, h in mm.
    mechanism : SliderCrank
        The fixed part of the mechanism.
    n_intervals : int
        Uniform time intervals over the revolution.

    Returns
    -------
    SliderCrankResult

    Raises
    ------
    InfeasibleDesignError
        If the crank cannot turn fully (r + |h| >= l).
    """
    start = time.perf_counter()
    design = check_design(design)
    m = require_assemblable(design, mechanism.ta_limits_deg)
    t = mechanism.motion.time_grid(n_intervals)
    tau = torque_curve(design, mechanism, t)
    theta, _, _ = mechanism.motion(t)
    x = slider_position(design, theta, mechanism.branch)[0]
    return SliderCrankResult(
        design=design, engine="analytic", t=t, tau=tau, theta=theta, x=x, t_rms=rms_over_cycle(t, tau),
        t_max=float(np.max(np.abs(tau))), margins=dict(zip(COLUMNS, map(float, m), strict=True)),
        dt=float(t[1] - t[0]), wall_time_s=time.perf_counter() - start)
