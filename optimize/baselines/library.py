"""Shared plumbing of the baselines that wrap maintained optimizer libraries (Optuna, SMT, pymoo, nevergrad).

The libraries are an optional extra: they are imported lazily, inside the baseline functions, through
:func:`require`, so mechopt imports and runs without them and a missing one gives a one-line error.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Iterable
from types import ModuleType

import numpy as np

from mechopt.errors import MechoptError
from mechopt.optimize.budget import CountedProblem

__all__ = ["GP_PEERS_HINT", "INSTALL_HINT", "MissingLibraryError", "rejected_value", "require", "worst_feasible_value"]

INSTALL_HINT = "install the compare extra: pip install 'mechopt[compare]'"
GP_PEERS_HINT = "install the gp-peers extra (PyTorch 2.13.0, CPU): pip install 'mechopt[gp-peers]'"


class MissingLibraryError(MechoptError, ImportError):
    """An optional optimizer library (or one of its own optional dependencies) is not installed."""


def require(module: str, purpose: str, hint: str = INSTALL_HINT) -> ModuleType:
    """Import an optional library or raise a one-line :class:`MissingLibraryError`.

    Parameters
    ----------
    module : str
        Dotted module name, e.g. ``"optuna"`` or ``"pymoo.algorithms.soo.nonconvex.ga"``.
    purpose : str
        Baseline that needs it, for the message (e.g. ``"optuna_tpe"``).
    hint : str, optional
        How to install it, default the ``compare`` extra.

    Returns
    -------
    module
        The imported module.
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        missing = getattr(exc, "name", None) or module
        raise MissingLibraryError(f"{purpose} needs the package {missing!r}; {hint}") from None


def worst_feasible_value(problem: CountedProblem) -> float:
    """Largest finite objective value simulated so far at a feasible design (NaN when there is none).

    Parameters
    ----------
    problem : CountedProblem

    Returns
    -------
    float
        In the objective's units.
    """
    values = [e.f for e in problem.history if e.feasible and math.isfinite(e.f)]
    return max(values) if values else math.nan


def kriging_values(problem: CountedProblem, designs: Iterable[np.ndarray]) -> np.ndarray:
    """Simulated values of designs as a Kriging model takes them, (n, 1): a failed simulation enters at the worst
    feasible value seen (else ``infeasible_value``), which pushes the search away from it; Kriging needs a number.

    Parameters
    ----------
    problem : CountedProblem
    designs : iterable of (d,) ndarray
        Designs in the variables' units.

    Returns
    -------
    (n, 1) ndarray
        In the objective's units.
    """
    out = []
    for x in designs:
        f = problem.evaluate(x)
        if not math.isfinite(f):
            worst = worst_feasible_value(problem)
            f = worst if math.isfinite(worst) else problem.infeasible_value
        out.append(f)
    return np.array(out, dtype=float).reshape(-1, 1)


def rejected_value(problem: CountedProblem, x: np.ndarray) -> float:
    """Value reported to a library for a design that is not simulated (infeasible, or whose simulation failed).

    ``worst + (1 + |worst|) * (1 + violation)``, with ``worst`` the worst feasible value simulated so far and the
    violation in unit-cube coordinates: above every simulated feasible value, so a ranking method puts it last, yet
    on the scale of the objective, so a model-based method (COBYLA, metamodels) is not wrecked by a 1e10 outlier, and
    growing with the violation, so the method sees the way back to the feasible region.

    Parameters
    ----------
    problem : CountedProblem
    x : ndarray, shape (d,)
        Design in the problem's units.

    Returns
    -------
    float
        In the objective's units; ``problem.infeasible_value`` plus the violation before any feasible simulation.
    """
    x = np.asarray(x, dtype=float)
    u = problem.to_unit(x)
    box = float(np.sum(np.maximum(-u, 0.0)) + np.sum(np.maximum(u - 1.0, 0.0)))
    margins = problem.margins(problem.clip(x))
    violation = box + float(np.sum(np.maximum(-margins, 0.0)))
    worst = worst_feasible_value(problem)
    if not math.isfinite(worst):
        return problem.infeasible_value * (1.0 + violation)
    return worst + (1.0 + abs(worst)) * (1.0 + violation)
