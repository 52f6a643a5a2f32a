"""Particle swarm optimisation with inertia weight and constriction coefficients, run to the budget.

Global-best PSO (Kennedy & Eberhart 1995; Shi & Eberhart 1998) with Clerc & Kennedy's (2002) constriction
``chi = 0.7298``, ``c1 = c2 = chi * 2.05 = 1.4962`` used as inertia weight and acceleration coefficients.  Velocities
are clamped to ``vmax_fraction`` of the box width; a particle leaving the box is put back on the face it crossed and
that velocity component is zeroed (absorbing wall).

Constraint handling: rejection with feasibility preservation (Hu & Eberhart 2002).  Particles start at feasible
designs; an infeasible position is not simulated, and only feasible positions may become personal or global bests,
so the swarm keeps being pulled towards the feasible region.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["minimize_particle_swarm"]

#: Clerc-Kennedy constriction with phi = 4.1, in its equivalent inertia-weight form.
CHI = 0.7298
C_ACC = CHI * 2.05


def minimize_particle_swarm(
    problem: CountedProblem,
    seed: int,
    *,
    n_particles: int = 20,
    inertia: float = CHI,
    c1: float = C_ACC,
    c2: float = C_ACC,
    vmax_fraction: float = 0.5,
) -> OptimizeResult:
    """Global-best PSO until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the initial swarm and of the random accelerations.
    n_particles : int, default 20
        Swarm size (paper 004 uses populations of 20).
    inertia, c1, c2 : float
        Inertia weight and cognitive / social coefficients (constriction values by default).
    vmax_fraction : float, default 0.5
        Velocity clamp as a fraction of the box width.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nit`` (swarm
        iterations).
    """
    rng = np.random.default_rng(seed)
    d = problem.dim
    pos = problem.sample_feasible(n_particles, rng)
    if pos.shape[0] == 0:
        return problem.result("no feasible initial particle found", nit=0)
    n = pos.shape[0]
    vmax = vmax_fraction * problem.span
    # SPSO-2006 initial velocity: half the way to a random point of the box.
    vel = 0.5 * (problem.from_unit(rng.random((n, d))) - pos)
    best_pos, best_val = pos.copy(), np.full(n, math.inf)
    g_pos, g_val = pos[0].copy(), math.inf
    n_it = 0
    try:
        for i in range(n):
            f = problem.evaluate(pos[i])
            best_val[i] = f if math.isfinite(f) else math.inf
            if best_val[i] < g_val:
                g_pos, g_val = pos[i].copy(), best_val[i]
        while True:
            for i in range(n):
                r1, r2 = rng.random(d), rng.random(d)
                vel[i] = inertia * vel[i] + c1 * r1 * (best_pos[i] - pos[i]) + c2 * r2 * (g_pos - pos[i])
                vel[i] = np.clip(vel[i], -vmax, vmax)
                pos[i] = pos[i] + vel[i]
                outside = (pos[i] < problem.lower) | (pos[i] > problem.upper)
                pos[i] = problem.clip(pos[i])
                vel[i, outside] = 0.0
                if not problem.feasible(pos[i]):
                    continue
                f = problem.evaluate(pos[i])
                if math.isfinite(f) and f < best_val[i]:
                    best_pos[i], best_val[i] = pos[i].copy(), f
                    if f < g_val:
                        g_pos, g_val = pos[i].copy(), f
            n_it += 1
    except BudgetExhausted as exc:
        return problem.result(str(exc), nit=n_it)
