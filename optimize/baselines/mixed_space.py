"""The variables of a counted problem as the peers' libraries declare them, and their proposals back as designs.

Each library has its documented way of saying that a variable is an integer or a value from a list, and each peer
uses it when the problem has discrete variables:

* continuous: Optuna ``FloatDistribution(l, u)``; SMT ``FloatVariable(0, 1)`` (the unit cube); pymoo
  ``Real(bounds=(l, u))``;
* grid of step ``s``: Optuna ``FloatDistribution(l, u, step=s)`` (``suggest_float(step=)``); SMT
  ``IntegerVariable(0, count - 1)``; pymoo ``Integer(bounds=(0, count - 1))``;
* integer: Optuna ``IntDistribution(l, u)`` (``suggest_int``); SMT ``IntegerVariable(l, u)``; pymoo
  ``Integer(bounds=(l, u))``;
* catalogue: Optuna ``CategoricalDistribution(values)`` (``suggest_categorical``); SMT ``OrdinalVariable(values)``;
  pymoo ``Choice(options=values)``.

A grid is an integer index ``k`` (value ``lower + k step``) for SMT and pymoo, whose integers are the library's
integers; Optuna has a stepped float.  A catalogue is ordinal for SMT (its index, in order) and a choice for pymoo
and Optuna (their categorical variables: pymoo and Optuna have no ordinal kind).  Every decoded design is snapped
with :meth:`~mechopt.optimize.variable.Variable.snap` so that it equals the allowed design bit for bit (a stepped
float of Optuna carries float noise) and the counted problem's store sees one key per allowed design.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mechopt.optimize.baselines.library import require
from mechopt.optimize.budget import CountedProblem
from mechopt.optimize.variable import Variable

__all__ = ["allowed_feasible", "from_optuna", "from_pymoo", "has_discrete", "optuna_space", "pymoo_variables", "snap",
           "variables_of"]


def variables_of(problem: CountedProblem) -> tuple[Variable, ...]:
    """The problem's variables (``problem.variables``), or continuous ones over its bounds when it has none."""
    declared = getattr(problem, "variables", None)
    if declared:
        return tuple(declared)
    return tuple(Variable(f"x{j}", float(lo), float(hi)) for j, (lo, hi) in enumerate(problem.bounds))


def has_discrete(problem: CountedProblem) -> bool:
    """Whether any variable of the problem is a grid, an integer or a catalogue."""
    return any(v.discrete for v in variables_of(problem))


def snap(problem: CountedProblem, X: np.ndarray) -> np.ndarray:
    """Designs (n, d) or (d,) moved to the nearest allowed design of the problem's variables."""
    X = np.asarray(X, dtype=float)
    out = np.array(X, ndmin=2, copy=True)
    for j, v in enumerate(variables_of(problem)):
        out[:, j] = v.snap(out[:, j])
    return out.reshape(X.shape)


def allowed_feasible(problem: CountedProblem, n: int, rng: np.random.Generator, *, exclude: np.ndarray | None = None,
                     max_draws: int = 2_000_000) -> np.ndarray:
    """Up to ``n`` distinct feasible allowed designs drawn uniformly in the box (cheap rejection sampling).

    Parameters
    ----------
    problem : CountedProblem
    n : int
        Designs wanted.
    rng : numpy.random.Generator
    exclude : (k, d) ndarray, optional
        Designs not to return (those already simulated).
    max_draws : int, default 2 000 000
        Uniform draws tried before giving up (a feasible region of 0.1 % of the box needs about 1000 n).

    Returns
    -------
    (m, d) ndarray
        ``m <= n`` designs, in the order drawn.
    """
    seen = {x.tobytes() for x in np.asarray(exclude, dtype=float).reshape(-1, problem.dim)} if exclude is not None \
        else set()
    found: list[np.ndarray] = []
    drawn, batch = 0, max(4096, 64 * n)
    while len(found) < n and drawn < max_draws:
        X = snap(problem, problem.from_unit(rng.random((batch, problem.dim))))
        drawn += batch
        for x in X[problem.feasible(X)]:
            key = x.tobytes()
            if key not in seen:
                seen.add(key)
                found.append(x)
                if len(found) == n:
                    break
    return np.array(found).reshape(-1, problem.dim)


def optuna_space(optuna: Any, problem: CountedProblem) -> dict[str, Any]:
    """Optuna distributions by parameter name (``x0``, ``x1``...): what ``suggest_float`` (with ``step`` on a grid),
    ``suggest_int`` and ``suggest_categorical`` declare."""
    dist = optuna.distributions
    space = {}
    for j, v in enumerate(variables_of(problem)):
        if v.kind == "catalogue":
            space[f"x{j}"] = dist.CategoricalDistribution(tuple(float(c) for c in v.values))
        elif v.kind == "integer":
            space[f"x{j}"] = dist.IntDistribution(int(v.lower), int(v.upper))
        elif v.kind == "grid":
            space[f"x{j}"] = dist.FloatDistribution(float(v.lower), float(v.upper), step=float(v.step))
        else:
            space[f"x{j}"] = dist.FloatDistribution(float(v.lower), float(v.upper))
    return space


def from_optuna(problem: CountedProblem, params: dict[str, Any]) -> np.ndarray:
    """The allowed design (d,) of an Optuna trial's parameters."""
    return snap(problem, np.array([float(params[f"x{j}"]) for j in range(problem.dim)]))


def pymoo_variables(problem: CountedProblem) -> dict[str, Any]:
    """pymoo's ``Real`` / ``Integer`` / ``Choice`` variables by name (``x0``, ``x1``...), a grid as its index."""
    variable = require("pymoo.core.variable", "pymoo_ga")
    out = {}
    for j, v in enumerate(variables_of(problem)):
        if v.kind == "catalogue":
            out[f"x{j}"] = variable.Choice(options=[float(c) for c in v.values])
        elif v.kind == "integer":
            out[f"x{j}"] = variable.Integer(bounds=(int(v.lower), int(v.upper)))
        elif v.kind == "grid":
            out[f"x{j}"] = variable.Integer(bounds=(0, int(v.count) - 1))
        else:
            out[f"x{j}"] = variable.Real(bounds=(float(v.lower), float(v.upper)))
    return out


def from_pymoo(problem: CountedProblem, values: dict[str, Any]) -> np.ndarray:
    """The allowed design (d,) of a pymoo individual (a dict by variable name)."""
    x = []
    for j, v in enumerate(variables_of(problem)):
        value = float(values[f"x{j}"])
        x.append(v.lower + value * v.step if v.kind == "grid" else value)
    return snap(problem, np.array(x))
