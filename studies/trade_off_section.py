"""A study file's trade-off keys: ``objective = ["t_rms", "-toggle_margin_deg"]`` (a leading ``-`` maximises) and a
``[limits]`` table (``t_rms = [0, 3.0]``, or ``t_rms = { upper = 3.0 }``), and the command line's ``--objective`` /
``--limit`` that override them.

Example::

    objective = ["t_rms", "-toggle_margin_deg"]

    [limits]
    t_max = { upper = 6.0 }          # N·m
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from typing import Any

from mechopt.errors import InputError, StudyError
from mechopt.optimize.objectives import parse_limit
from mechopt.optimize.problem import DesignProblem

__all__ = ["command_line_trade_off", "with_objectives", "with_trade_off"]


def _limit_pair(name: str, value: Any, where: str) -> tuple[float | None, float | None]:
    if isinstance(value, Mapping):
        unknown = sorted(set(value) - {"lower", "upper"})
        if unknown:
            raise StudyError(f"{where}: unknown key limits.{name}.{unknown[0]}; expected lower, upper")
        return value.get("lower"), value.get("upper")
    if isinstance(value, Sequence) and not isinstance(value, str) and len(value) == 2:
        return value[0], value[1]
    raise StudyError(f"{where}: limits.{name} = {value!r}; expected [lower, upper] or {{ upper = ... }}")


def with_objectives(problem: DesignProblem, objective: Any = None,
                    limits: Mapping[str, tuple[float | None, float | None]] | None = None) -> DesignProblem:
    """A copy of ``problem`` with these objectives and limits (None: the problem's own), checked.

    Raises
    ------
    InputError
        An objective or a limit naming no output, more than four objectives, lower > upper (one line).
    """
    if objective is None and limits is None:
        return problem
    new = copy.copy(problem)
    if objective is not None:
        object.__setattr__(new, "objective", tuple(objective) if not isinstance(objective, str) else objective)
    if limits is not None:
        object.__setattr__(new, "limits", dict(limits))
    new.check()
    return new


def with_trade_off(file: Any, problem: DesignProblem) -> DesignProblem:
    """The study's problem with the file's ``objective`` and ``[limits]``, when it has them.

    Parameters
    ----------
    file : StudyFile
        The parsed study file (its keys read are recorded, so unknown keys are still refused).
    problem : DesignProblem
        The plug-in's problem.
    """
    config = file.config
    objective = config.get("objective") if not isinstance(config.get("objective"), Mapping) else None
    if objective is not None:
        file.read.add("objective")
        if isinstance(objective, str):
            objective = [objective]
    limits = None
    if "limits" in config:
        table = file.table("limits")
        limits = {name: _limit_pair(name, value, file.where) for name, value in table.items()}
    try:
        return with_objectives(problem, objective, limits)
    except InputError as exc:
        raise StudyError(f"{file.where}: {exc}") from None


def command_line_trade_off(problem: DesignProblem, objective: str | None,
                           limits: Sequence[str] | None) -> DesignProblem:
    """The problem with ``--objective t_rms,-toggle_margin_deg`` and ``--limit "t_rms<=3.0"`` (repeatable) applied;
    a ``--limit`` adds to (or replaces, for the same output) the study's limits."""
    names = None if not objective else [n.strip() for n in objective.split(",") if n.strip()]
    merged = None
    if limits:
        merged = dict(problem.limits)
        merged.update(parse_limit(text) for text in limits)
    return with_objectives(problem, names, merged)
