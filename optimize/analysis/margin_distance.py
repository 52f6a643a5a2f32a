"""How far a design lies from each of its active margins, in the variables' units, and whether a tolerance makes a
margin fail: the lines every study report carries under its optimum."""

from __future__ import annotations

from typing import Any

import numpy as np

from mechopt.optimize.analysis.scatter import Tolerances
from mechopt.optimize.analysis.scatter_statistics import violation_probabilities
from mechopt.optimize.problem import DesignProblem

__all__ = ["ACTIVE", "default_tolerances", "margin_distances"]

#: A margin is active when moving the design by this fraction of each variable's range along the margin's gradient
#: would make it fail, or when the tolerances make it fail on some parts.
ACTIVE = 0.01
#: Tolerance assumed when a study declares none: 0.1 of the unit for lengths in mm (a drawing's default), else this
#: fraction of the variable's range.
DEFAULT_MM = 0.1
DEFAULT_FRACTION = 1e-3


def default_tolerances(problem: DesignProblem) -> Tolerances:
    """±0.1 mm on lengths in mm, ±0.1 % of the range on any other variable (uniform)."""
    return Tolerances({v.name: DEFAULT_MM if v.unit == "mm" else DEFAULT_FRACTION * (v.upper - v.lower)
                       for v in problem.variables})


def _gradient(problem: DesignProblem, x: np.ndarray) -> np.ndarray:
    """Central differences (n_constraints, d) of the margins at x, steps of 1e-6 of each range."""
    h = 1e-6 * (problem.bounds[:, 1] - problem.bounds[:, 0])
    E = np.diag(h)
    M = problem.constraint_margins(np.vstack([x + E, x - E]))
    d = problem.dim
    return ((M[:d] - M[d:]) / (2.0 * h[:, None])).T


def margin_distances(problem: DesignProblem, x: Any, tolerances: Tolerances | None = None) -> dict[str, Any]:
    """The active margins of design ``x``: each one's value, the distance to it along each variable and along its
    gradient, and the probability a tolerance makes it fail.

    Parameters
    ----------
    problem : DesignProblem
        The problem.
    x : (d,) array_like
        The design, in the variables' units.
    tolerances : Tolerances, optional
        The study's; default :func:`default_tolerances`.

    Returns
    -------
    dict
        ``active`` (per constraint: ``margin``, ``along`` {variable: signed move in its unit that zeroes the
        linearised margin}, ``nearest`` (the move along the gradient, in the variables' units when they share
        one), ``violation`` (probability under the tolerances)), ``tolerances`` (the description) and ``lines``
        (Markdown for a report, warnings included).
    """
    x = np.asarray(x, dtype=float).ravel()
    if not problem.constraints:
        return {"active": {}, "tolerances": "", "lines": []}
    tol = tolerances or default_tolerances(problem)
    m = problem.constraint_margins(x[None, :])[0]
    G = _gradient(problem, x)
    w = problem.bounds[:, 1] - problem.bounds[:, 0]
    p, _, _ = violation_probabilities(problem, x + tol.deviations(problem, n=2**12))
    units = {v.unit for v in problem.variables}
    unit = f" {units.pop()}" if len(units) == 1 else " (variables' units)"
    active, lines = {}, []
    for j, c in enumerate(problem.constraints):
        g = G[j]
        scaled = float(np.linalg.norm(g * w))
        if not np.isfinite(m[j]) or scaled == 0.0 or (m[j] / scaled > ACTIVE and p[c] == 0.0):
            continue
        along = {v.name: float(-m[j] / gi) for v, gi in zip(problem.variables, g, strict=True) if gi != 0.0}
        nearest = float(m[j] / np.linalg.norm(g))
        active[c] = {"margin": float(m[j]), "along": along, "nearest": nearest, "violation": p[c]}
        moves = ", ".join(f"{n} {d:+.4g}{(' ' + problem.variables[problem.names.index(n)].unit)}"
                          for n, d in along.items())
        lines.append(f"- `{c}` = {m[j]:.4g}: reached by moving {moves} (alone), or {abs(nearest):.4g}{unit} along "
                     "its gradient")
        if p[c] > 0.0:
            lines.append(f"  - **warning**: under {tol.describe(problem)} it fails on {100 * p[c]:.1f} % of the parts")
    head = [f"Active margins of the optimum (tolerances {tol.describe(problem)}):"] if active else \
        ["No margin is active at the optimum."]
    return {"active": active, "tolerances": tol.describe(problem), "lines": head + lines}
