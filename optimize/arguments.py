"""The checks of :func:`mechopt.minimize`'s arguments, shared with the command line so both refuse the same values
with the same one-line message, before any simulation."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from mechopt.errors import InputError

__all__ = ["AUTO_METHOD", "MIN_BUDGET", "SPARSE_METHODS", "available_methods", "check_budget", "check_method",
           "check_seed", "check_workers", "check_x0", "handles_dim", "method_min_budget"]

#: The fewest simulations any method is given: a model needs a few designs before it can propose one.
MIN_BUDGET = 3

#: The line-model methods of paper 002 (``mechopt.optimize.sparse`` and ``mechopt.optimize.sparse_global``).
SPARSE_METHODS = ("sparse", "sparse-global")

#: The default method of :func:`mechopt.minimize` (:mod:`mechopt.optimize.auto`): its plan follows d and the budget.
AUTO_METHOD = "auto"
#: The method of :func:`mechopt.minimize` and of a study that names none.
DEFAULT_METHOD = AUTO_METHOD


def _baselines() -> dict[str, Callable[..., Any]]:
    from mechopt.optimize.baselines import BASELINES

    return BASELINES


def available_methods() -> list[str]:
    """Every method name :func:`mechopt.minimize` and ``mechopt study --method`` accept."""
    return [AUTO_METHOD, *SPARSE_METHODS, *_baselines()]


def _whole(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | np.integer)


def check_budget(budget: Any) -> int:
    """``budget`` as an int, or an :class:`InputError` naming it (a whole number of simulations >= 3)."""
    if not _whole(budget) or budget < MIN_BUDGET:
        raise InputError(f"budget = {budget!r}: expected a whole number of simulations >= {MIN_BUDGET}")
    return int(budget)


def check_seed(seed: Any) -> int:
    """``seed`` as an int, or an :class:`InputError` naming it (a whole number >= 0)."""
    if not _whole(seed) or seed < 0:
        raise InputError(f"seed = {seed!r}: expected a whole number >= 0")
    return int(seed)


def check_workers(workers: Any) -> int | None:
    """``workers`` (None: every core), or an :class:`InputError` naming it (a whole number >= 1)."""
    if workers is not None and (not _whole(workers) or workers < 1):
        raise InputError(f"workers = {workers!r}: expected a whole number >= 1")
    return workers


def check_x0(problem: Any, x0: Any, budget: int) -> np.ndarray | None:
    """``x0`` as an (m, d) array of designs inside the box that satisfy the declared constraints and leave the
    method a budget (None when not given), or an :class:`InputError` naming the offending design."""
    if x0 is None:
        return None
    try:
        X = np.array(x0, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"x0 = {x0!r}: expected a design of {problem.dim} numbers, or a list of such "
                         "designs") from None
    X = X[None, :] if X.ndim == 1 else X
    if X.ndim != 2 or X.shape[1] != problem.dim or X.shape[0] == 0:
        raise InputError(f"x0 of shape {np.shape(x0)}: expected ({problem.dim},) or (m, {problem.dim}) for the "
                         f"variables {', '.join(problem.names)}")
    bounds = problem.bounds
    for x in X:
        if not np.all(np.isfinite(x)):
            raise InputError(f"x0 design {x.tolist()} is not finite")
        outside = np.flatnonzero((x < bounds[:, 0]) | (x > bounds[:, 1]))
        if outside.size:
            v = problem.variables[int(outside[0])]
            raise InputError(f"x0 design {x.tolist()}: {v.name} = {x[outside[0]]:g} lies outside [{v.lower:g}, "
                             f"{v.upper:g}]" + (f" {v.unit}" if v.unit else ""))
    infeasible = np.flatnonzero(~problem.feasible(X))
    if infeasible.size:
        x = X[infeasible[0]]
        margins = problem.constraint_margins(x[None, :])[0] if problem.constraints else np.zeros(0)
        failing = [f"{c} = {m:.4g}" for c, m in zip(problem.constraints, margins, strict=True) if not m >= 0.0]
        raise InputError(f"x0 design {problem.describe(x)} violates the declared constraints"
                         + (f": {', '.join(failing)} (margins must be >= 0)" if failing else ""))
    if X.shape[0] >= budget:
        raise InputError(f"x0 holds {X.shape[0]} designs and the budget is {budget}: the designs of x0 count in the "
                         "budget and leave the method none")
    return X


def check_method(method: Any, dim: int, name: str = "the problem", budget: int | None = None,
                 n_lines: int | None = None) -> None:
    """Refuse an unknown method name, a line-model method outside its 2 to 4 design variables, or a budget below
    the method's own minimum (:func:`method_min_budget`).

    Parameters
    ----------
    method : str or callable
        A name of :func:`available_methods`, or ``f(counted_problem, seed) -> OptimizeResult``.
    dim : int
        The problem's number of design variables.
    name : str
        The problem's name, for the message.
    budget : int, optional
        The budget (checked against the method's minimum when given).
    n_lines : int, optional
        Lines of the sparse method's global model when the caller's options set them (default: the plan scaled to
        the budget).
    """
    if callable(method):
        return
    if method not in available_methods():
        raise InputError(f"method = {method!r}; expected one of {', '.join(available_methods())} or a callable")
    if not handles_dim(method, dim):
        raise InputError(f"method {method!r} handles 2 to 4 design variables; {name!r} has {dim}: choose 'auto' "
                         "or a baseline (`--method`, `mechopt methods`)")
    if budget is None:
        return
    need, why = method_min_budget(method, dim, budget, n_lines)
    if budget < need:
        raise InputError(f"budget = {budget}: method {method!r} needs at least {why} = {need} simulations for the "
                         f"{dim} variables of {name!r}")


def handles_dim(method: str, dim: int) -> bool:
    """Whether a method takes ``dim`` design variables: the line models 2 to 4, every other method any number."""
    return method not in SPARSE_METHODS or 2 <= dim <= 4


def method_min_budget(method: str, dim: int, budget: int = MIN_BUDGET, n_lines: int | None = None) -> tuple[int, str]:
    """The fewest simulations a mechopt method is given for ``dim`` variables, and the rule in words.

    ``auto`` needs 2d + 2 (its Sobol design and a model step); ``sparse`` two samples on each line of its global
    model and one to confirm the model's candidate (lines: ``n_lines``, or the plan scaled to ``budget``), since a
    line plan trimmed to fewer would run past the budget; ``sparse-global`` 10·d (its lines and the steps on them).
    A baseline needs :data:`MIN_BUDGET`.
    """
    if method == AUTO_METHOD:
        return 2 * dim + 2, "2d + 2"
    if method == "sparse":
        from mechopt.optimize.sparse.options import SparseOptions

        lines = int(n_lines) if n_lines is not None else SparseOptions.for_budget(budget, dim).n_lines
        return 2 * lines + 1, f"2 samples on each of its {lines} lines + 1"
    if method == "sparse-global":
        return 10 * dim, "10d"
    return MIN_BUDGET, str(MIN_BUDGET)
