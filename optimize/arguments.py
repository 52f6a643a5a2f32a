"""The checks of :func:`mechopt.minimize`'s arguments, shared with the command line so both refuse the same values
with the same one-line message, before any simulation."""

from __future__ import annotations

from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.methods import AUTO_METHOD, DEFAULT_METHOD, MIN_BUDGET, available_methods, get_method
from mechopt.runs.sample_record import KEY_DECIMALS

__all__ = ["AUTO_METHOD", "DEFAULT_METHOD", "MIN_BUDGET", "available_methods", "check_budget", "check_method",
           "check_seed", "check_workers", "check_x0", "handles_dim", "method_min_budget"]


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
    _check_on_grid(problem, X)
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


def _check_on_grid(problem: Any, X: np.ndarray) -> None:
    """Refuse a design of x0 whose discrete variable holds a value it does not allow: the designs a method starts
    from are simulated as given, and a rounded one may break a constraint the user's design met (the ventilator's
    continuous optimum rounded to 0.1 mm does)."""
    for x in X:
        for v, value in zip(problem.variables, x, strict=True):
            if not v.discrete or abs(float(v.snap(value)) - value) <= 10.0 ** -(KEY_DECIMALS - 1):
                continue
            allowed = v.allowed()
            i = int(np.searchsorted(allowed, value))
            below, above = allowed[max(i - 1, 0)], allowed[min(i, allowed.size - 1)]
            raise InputError(f"x0 design {x.tolist()}: {v.name} = {value:g} is not an allowed value "
                             f"({v.describe_kind()}); expected an allowed value such as {below:g} or {above:g}")


def check_method(method: Any, dim: int, name: str = "the problem", budget: int | None = None,
                 n_lines: int | None = None) -> None:
    """Refuse an unknown method name, a method outside the dimensions it takes, or a budget below the method's own
    minimum (:func:`method_min_budget`); each as read from the table of methods
    (:data:`mechopt.optimize.methods.METHODS`).

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
    record = get_method(method)
    if not record.takes_dim(dim):
        raise InputError(f"method {method!r} handles {record.dims_text()} design variables; {name!r} has {dim}: "
                         f"choose {DEFAULT_METHOD!r} or a baseline (`--method`, `mechopt methods`)")
    if budget is None:
        return
    need, why = method_min_budget(method, dim, budget, n_lines)
    if budget < need:
        raise InputError(f"budget = {budget}: method {method!r} needs at least {why} = {need} simulations for the "
                         f"{dim} variables of {name!r}")


def handles_dim(method: str, dim: int) -> bool:
    """Whether a method takes ``dim`` design variables (the line models 2 to 4, every other method any number)."""
    return get_method(method).takes_dim(dim)


def method_min_budget(method: str, dim: int, budget: int = MIN_BUDGET, n_lines: int | None = None) -> tuple[int, str]:
    """The fewest simulations a method is given for ``dim`` variables, and the rule in words (its record's
    ``min_budget``): ``auto`` 2d + 2, ``sparse`` two samples on each line of its global model (``n_lines``, or the
    plan scaled to ``budget``) and one to confirm, ``sparse-global`` 10·d, a baseline :data:`MIN_BUDGET`."""
    return get_method(method).min_budget(dim, budget, n_lines)
