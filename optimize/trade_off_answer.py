"""The answer of a trade-off run: the feasible Pareto front of the simulated designs, or the best feasible design under
limits, or — when no simulated design meets every margin and limit — the designs that come closest, marked so."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.pareto import front_mask, hypervolume, hypervolume_trace, normalisation
from mechopt.optimize.problem import DesignProblem

__all__ = ["CLOSEST", "declared_scale", "trade_off_answer", "violation"]

#: Designs returned when none is feasible: the ones that break the margins and limits least.
CLOSEST = 5


def declared_scale(problem: DesignProblem) -> tuple[np.ndarray, np.ndarray] | None:
    """The problem's ``ideal`` and ``nadir`` (minimised objectives, both or neither), checked in one line."""
    ideal, nadir = getattr(problem, "ideal", None), getattr(problem, "nadir", None)
    if ideal is None or nadir is None:
        return None
    k = problem.objective_spec.k
    ideal, nadir = np.asarray(ideal, dtype=float).ravel(), np.asarray(nadir, dtype=float).ravel()
    if ideal.size != k or nadir.size != k or not (np.all(np.isfinite(ideal)) and np.all(nadir > ideal)):
        raise InputError(f"ideal = {ideal.tolist()}, nadir = {nadir.tolist()}; expected {k} finite values each, "
                         "every nadir above its ideal (minimised objectives)")
    return ideal, nadir


def violation(problem: DesignProblem, X: np.ndarray, G: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """How far each design (n,) lies outside the margins and limits: the sum over them of the amount broken, each
    divided by that output's (margin's) spread over the designs; 0 when feasible, inf when the simulation failed."""
    limits = problem.limit_spec
    parts = [limits.violation(G)] if limits.m else []
    inside = problem.in_box(X)
    if problem.constraints:
        M = np.full((X.shape[0], len(problem.constraints)), -np.inf)
        if inside.any():
            M[inside] = problem.constraint_margins(X[inside])
        parts.append(np.maximum(-M, 0.0))
    if not parts:
        total = np.zeros(X.shape[0])
    else:
        V = np.hstack(parts)
        finite = np.where(np.isfinite(V), V, np.nan)
        spread = np.nanmax(finite, axis=0) if np.isfinite(finite).any() else np.ones(V.shape[1])
        spread = np.where(np.isfinite(spread) & (spread > 0), spread, 1.0)
        total = np.sum(V / spread, axis=1)
    return np.where(ok & inside, total, np.inf)


def trade_off_answer(problem: DesignProblem, X: np.ndarray, F: np.ndarray, G: np.ndarray, ok: np.ndarray,
                     outputs: Sequence[Mapping[str, Any] | None]) -> dict[str, Any]:
    """The result fields of a trade-off run over every design it simulated.

    Parameters
    ----------
    problem : DesignProblem
        The problem (objectives, limits, margins).
    X : (n, d) ndarray
        Designs simulated, in order, in the variables' units.
    F : (n, k) ndarray
        Minimised objectives (NaN: failed).
    G : (n, m) ndarray
        Limited outputs.
    ok : (n,) bool ndarray
        Simulations that succeeded.
    outputs : sequence of dict or None
        Every output of each design (None: failed).

    Returns
    -------
    dict
        ``x``, ``fun``, ``success``, ``message``, ``feasible`` (per returned design), ``front_outputs``,
        ``simulated`` (X, F, G, ok, feasible of every design) and, with several objectives, ``hypervolume``,
        ``reference_point``, ``normalisation`` and ``hypervolume_trace``.
    """
    spec, limits = problem.objective_spec, problem.limit_spec
    V = violation(problem, X, G, ok)
    feasible = V == 0.0
    simulated = {"X": X, "F": F, "G": G, "ok": ok, "feasible": feasible}
    if not feasible.any():
        return _closest(problem, X, F, V, outputs, simulated)
    idx = np.flatnonzero(feasible)
    if spec.k == 1:
        i = int(idx[np.argmin(F[idx, 0])])
        return {"x": X[i].copy(), "fun": float(F[i, 0]), "success": True, "feasible": np.array([True]),
                "front_outputs": [dict(outputs[i] or {})], "simulated": simulated,
                "message": f"the best of {int(feasible.sum())} simulated designs meeting "
                           f"{limits.describe() or 'the margins'}"}
    front = idx[front_mask(F[idx])]
    front = front[np.argsort(F[front, 0], kind="stable")]
    norm = normalisation(F[front], *(declared_scale(problem) or (None, None)))
    hv = hypervolume(F[front], norm)
    return {"x": X[front].copy(), "fun": F[front].copy(), "success": True, "feasible": np.ones(front.size, bool),
            "front_outputs": [dict(outputs[i] or {}) for i in front], "front_index": front,
            "hypervolume": hv, "reference_point": norm.reference_point, "normalisation": norm.description,
            "hypervolume_trace": hypervolume_trace(F, feasible, norm), "simulated": simulated,
            "message": f"{front.size} non-dominated designs of {int(feasible.sum())} feasible ones "
                       f"({', '.join(spec.labels)}), hypervolume {hv:.4g}"}


def _closest(problem: DesignProblem, X: np.ndarray, F: np.ndarray, V: np.ndarray,
             outputs: Sequence[Mapping[str, Any] | None], simulated: dict[str, Any]) -> dict[str, Any]:
    """No feasible design: the ones that break the margins and limits least, marked infeasible."""
    spec, limits = problem.objective_spec, problem.limit_spec
    what = limits.describe() or "the declared margins"
    order = np.argsort(V, kind="stable")
    order = order[np.isfinite(V[order])][: (1 if spec.k == 1 else CLOSEST)]
    base = {"success": False, "simulated": simulated, "feasible": np.zeros(order.size, bool),
            "front_outputs": [dict(outputs[i] or {}) for i in order]}
    if not order.size:
        d = X.shape[1] if X.ndim == 2 else problem.dim
        return {**base, "x": np.full(d, np.nan) if spec.k == 1 else np.zeros((0, d)),
                "fun": float("nan") if spec.k == 1 else np.zeros((0, spec.k)),
                "message": "no simulation succeeded"}
    message = (f"no simulated design meets {what}: returned the {order.size} that come closest, marked infeasible "
               f"(the closest: {problem.describe(X[order[0]])}")
    if limits.m and outputs[order[0]]:
        message += ", " + ", ".join(f"{n} = {outputs[order[0]].get(n, float('nan')):.4g}" for n in limits.names)
    message += ")"
    if spec.k == 1:
        return {**base, "x": X[order[0]].copy(), "fun": float(F[order[0], 0]), "message": message,
                "outputs": base["front_outputs"][0]}
    return {**base, "x": X[order].copy(), "fun": F[order].copy(), "message": message}
