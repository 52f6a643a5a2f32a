"""The default method's plan for a least-squares problem: multi-level single linkage over a growing Sobol sample,
Gauss-Newton runs on the residuals from its starts, until the budget is spent.

Each round adds a Sobol batch to the sample, then runs Gauss-Newton from every start MLSL admits (best first).  A
run may spend at most a third of what is left, so that one long valley cannot take the whole budget from the other
basins; the sample rounds keep the search global.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np
from scipy.stats import qmc

from mechopt.optimize.least_squares import choose_starts, critical_distance, gauss_newton

__all__ = ["least_squares_plan"]

#: Starts tried per round before the sample grows again.
STARTS_PER_ROUND = 3
#: An exploring run stops when a Jacobian's worth of simulations (d + 1) gained less than this share of its sum of
#: squares: the rest of a slow, linear convergence is spent only on the best design (the final polish).
STALL = 0.01


class _ResidualRun(Protocol):
    U: np.ndarray
    values: np.ndarray
    R: list
    rng: np.random.Generator
    remaining: int

    def allowed(self, U: np.ndarray) -> np.ndarray: ...
    def simulate(self, U: np.ndarray) -> None: ...
    def residuals_at(self, U: np.ndarray) -> tuple[np.ndarray, list]: ...
    def declared(self, U: np.ndarray) -> np.ndarray: ...
    def fill(self, U: np.ndarray, k: int) -> np.ndarray: ...


def least_squares_plan(run: _ResidualRun, batch: int, step: float,
                       margins: Callable[[np.ndarray], np.ndarray] | None) -> list[str]:
    """Spend the rest of ``run``'s budget on MLSL starts and Gauss-Newton runs; returns one line per local run.

    Exploring runs stop once they stall (:data:`STALL`); the last tenth of the budget (at least 5 Jacobians' worth)
    runs the best design found to convergence, and exploration resumes if that leaves budget over.

    Parameters
    ----------
    run : _Run of :mod:`mechopt.optimize.auto.search`
        The designs simulated so far, with their residuals.
    batch : int
        Designs simulated together.
    step : float
        Forward-difference step (unit cube).
    margins : callable, optional
        ``margins(U) -> (n, c)`` of the declared constraints in unit-cube coordinates.
    """
    d = run.U.shape[1]
    reserve = max(5 * (d + 1), (run.remaining + run.U.shape[0]) // 10)
    state = _Exploration(run, d)
    polished: set[int] = set()
    lines: list[str] = []
    while run.remaining > 0:
        best = _best(run)
        if best is not None and run.remaining <= reserve and best not in polished:
            polished.add(best)
            lines.append(state.local(best, run.remaining, 0.0, batch, step, margins))
            # The polish's own end is polished: only a better basin found by exploration earns another.
            polished.add(_best(run))
            continue
        for i in state.starts():
            if run.remaining <= (reserve if best not in polished else 0):
                break
            lines.append(state.local(i, max(d + 2, run.remaining // 3), STALL, batch, step, margins))
        if run.remaining > 0:
            state.grow(max(2 * d + 2, batch))
    return lines


def _best(run: _ResidualRun) -> int | None:
    ok = np.isfinite(run.values) & np.array([r is not None for r in run.R], dtype=bool)
    return int(np.argmin(np.where(ok, run.values, np.inf))) if ok.any() else None


class _Exploration:
    """The MLSL bookkeeping: the Sobol sample's continuation, the designs local runs visited, the starts used."""

    def __init__(self, run: _ResidualRun, d: int) -> None:
        self.run, self.d = run, d
        self.sobol = qmc.Sobol(d, seed=run.rng)
        self.sobol.fast_forward(run.U.shape[0])
        self.explored = np.zeros((0, d))
        self.used: set[int] = set()
        self.starved = False

    def starts(self) -> np.ndarray:
        run = self.run
        ok = np.isfinite(run.values) & np.array([r is not None for r in run.R], dtype=bool)
        values = np.where(ok, run.values, np.nan)
        values[list(self.used)] = np.nan
        found = choose_starts(run.U, values, self.explored, critical_distance(int(ok.sum()), self.d),
                              STARTS_PER_ROUND)
        self.starved = found.size == 0
        return found

    def local(self, i: int, budget: int, stall: float, batch: int, step: float,
              margins: Callable[[np.ndarray], np.ndarray] | None) -> str:
        run = self.run
        self.used.add(int(i))
        local = gauss_newton(run.residuals_at, run.U[i], np.asarray(run.R[i]), float(run.values[i]),
                             budget=budget, step=step, batch=batch, allowed=run.declared, margins=margins,
                             stall=stall)
        self.explored = np.vstack([self.explored, *local.visited])
        return f"from design {i}: {local.value:.6g} in {local.nfev} simulations ({local.message})"

    def grow(self, n: int) -> None:
        _grow_sample(self.run, self.sobol, n, self.starved)


def _grow_sample(run: _ResidualRun, sobol: qmc.Sobol, n: int, starved: bool) -> None:
    """Simulate the next ``n`` allowed Sobol designs (twice as many when no start was left to take)."""
    n = min(run.remaining, 2 * n if starved else n)
    chosen = np.zeros((0, run.U.shape[1]))
    for _ in range(20):
        C = sobol.random(max(8, 2 * n))
        chosen = np.vstack([chosen, C[run.allowed(C)]])
        if chosen.shape[0] >= n:
            break
    run.simulate(run.fill(chosen[:n], n))
