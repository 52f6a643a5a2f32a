"""Objectives and limits of a design problem: which outputs are minimised or maximised, and which must stay in a range.

Sign convention
---------------
A problem's ``objective`` is one output name or a tuple of 1 to :data:`MAX_OBJECTIVES` of them.  Every objective is
minimised; a leading ``-`` maximises the output instead (``"-toggle_margin_deg"``: the largest toggle margin).  Inside
the methods and in ``result.fun`` an objective is always the value minimised, that is the output times its sense
(+1, or -1 for a maximised one); ``result.outputs`` / ``result.front_outputs`` hold the outputs themselves.

``limits`` maps an output name to ``(lower, upper)`` in the output's unit, either side ``None`` (no bound there).  A
simulated design whose output lies outside its range is kept in the sample store and is infeasible in every answer.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mechopt.errors import InputError

__all__ = ["MAX_OBJECTIVES", "DeclaredObjectives", "Limits", "ObjectiveSpec", "parse_limit", "parse_objective"]

#: Most objectives a problem may have: a front in more dimensions needs far more designs than a simulator affords.
MAX_OBJECTIVES = 4


@dataclass(frozen=True)
class ObjectiveSpec:
    """Parsed objectives.

    Attributes
    ----------
    names : tuple of str
        The outputs, without the ``-`` of a maximised one.
    senses : tuple of float
        +1.0 for a minimised output, -1.0 for a maximised one.
    """

    names: tuple[str, ...]
    senses: tuple[float, ...]

    @property
    def k(self) -> int:
        """Number of objectives."""
        return len(self.names)

    @property
    def labels(self) -> tuple[str, ...]:
        """The objectives as written (``-`` before a maximised one)."""
        return tuple(("-" if s < 0 else "") + n for n, s in zip(self.names, self.senses, strict=True))

    def values(self, outputs: Mapping[str, Any]) -> np.ndarray:
        """The minimised values (k,) of one design's outputs; NaN where an output is missing or not a number."""
        return np.array([s * _number(outputs.get(n)) for n, s in zip(self.names, self.senses, strict=True)])


def _number(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return math.nan
    return float(value)


def parse_objective(objective: Any, outputs: Sequence[str], where: str) -> ObjectiveSpec:
    """Check and parse a problem's ``objective``.

    Parameters
    ----------
    objective : str or sequence of str
        One output name or 1 to 4 of them; a leading ``-`` maximises that output.
    outputs : sequence of str
        The outputs the problem declares.
    where : str
        What to name in an error (``"problem 'ventilator'"``).

    Raises
    ------
    InputError
        Not names, none or more than four, a name that is no output, or an output twice.
    """
    items = [objective] if isinstance(objective, str) else objective
    if not isinstance(items, Sequence) or not all(isinstance(n, str) for n in items):
        raise InputError(f"{where}: objective = {objective!r}; expected an output name or a list of 1 to "
                         f"{MAX_OBJECTIVES} of them, such as ('t_rms', '-toggle_margin_deg')")
    if not 1 <= len(items) <= MAX_OBJECTIVES:
        raise InputError(f"{where}: objective has {len(items)} names {list(items)}; expected 1 to {MAX_OBJECTIVES}")
    names, senses = [], []
    for item in items:
        text = item.strip()
        name = text[1:].strip() if text.startswith(("-", "+")) else text
        if name not in outputs:
            raise InputError(f"{where}: objective {item!r} names no output; expected one of {list(outputs)} "
                             "(a leading '-' maximises it)")
        names.append(name)
        senses.append(-1.0 if text.startswith("-") else 1.0)
    if len(set(names)) != len(names):
        raise InputError(f"{where}: objective {list(items)} names an output twice")
    return ObjectiveSpec(tuple(names), tuple(senses))


@dataclass(frozen=True)
class Limits:
    """Ranges the simulated outputs must stay in.

    Attributes
    ----------
    names : tuple of str
        The limited outputs.
    lower, upper : (m,) ndarray
        Bounds in the outputs' units; -inf / +inf where a side is open.
    """

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray

    @classmethod
    def parse(cls, limits: Any, outputs: Sequence[str], where: str) -> Limits:
        """Check a problem's ``limits`` mapping (name -> (lower, upper), either None) and parse it.

        Raises
        ------
        InputError
            Not a mapping, an output that is not declared, a bound that is not a finite number, both bounds None,
            or lower > upper.
        """
        if limits is None:
            limits = {}
        if not isinstance(limits, Mapping):
            raise InputError(f"{where}: limits = {limits!r:.80}; expected a mapping such as "
                             "{'t_rms': (None, 3.0)}")
        names, lower, upper = [], [], []
        for name, pair in limits.items():
            if name not in outputs:
                raise InputError(f"{where}: limit on {name!r} names no output; expected one of {list(outputs)}")
            if isinstance(pair, str) or not isinstance(pair, Sequence) or len(pair) != 2:
                raise InputError(f"{where}: limit on {name!r} = {pair!r}; expected (lower, upper), either None")
            lo, hi = (_bound(name, side, v, where) for side, v in zip(("lower", "upper"), pair, strict=True))
            if lo is None and hi is None:
                raise InputError(f"{where}: limit on {name!r} has neither a lower nor an upper bound")
            lo_f = -math.inf if lo is None else lo
            hi_f = math.inf if hi is None else hi
            if lo_f > hi_f:
                raise InputError(f"{where}: limit on {name!r} has lower {lo_f:g} > upper {hi_f:g}; expected "
                                 "lower <= upper")
            names.append(name)
            lower.append(lo_f)
            upper.append(hi_f)
        return cls(tuple(names), np.array(lower, dtype=float), np.array(upper, dtype=float))

    @property
    def m(self) -> int:
        """Number of limited outputs."""
        return len(self.names)

    def values(self, outputs: Mapping[str, Any]) -> np.ndarray:
        """The limited outputs (m,) of one design; NaN where missing."""
        return np.array([_number(outputs.get(n)) for n in self.names])

    def violation(self, G: np.ndarray) -> np.ndarray:
        """How far outputs G (n, m) lie outside their ranges, per limit (n, m), in the outputs' units (0: met)."""
        G = np.atleast_2d(np.asarray(G, dtype=float))
        with np.errstate(invalid="ignore"):
            v = np.maximum(np.maximum(self.lower - G, G - self.upper), 0.0)
        return np.where(np.isnan(v), np.inf, v)

    def met(self, G: np.ndarray) -> np.ndarray:
        """Designs (n,) whose outputs G (n, m) meet every limit."""
        return np.all(self.violation(G) == 0.0, axis=1)

    def describe(self) -> str:
        """The limits as written by a user, e.g. ``t_rms <= 3, 10 <= toggle_margin_deg``."""
        parts = []
        for n, lo, hi in zip(self.names, self.lower, self.upper, strict=True):
            if np.isfinite(lo) and np.isfinite(hi):
                parts.append(f"{lo:g} <= {n} <= {hi:g}")
            elif np.isfinite(hi):
                parts.append(f"{n} <= {hi:g}")
            else:
                parts.append(f"{n} >= {lo:g}")
        return ", ".join(parts)


def _bound(name: str, side: str, value: Any, where: str) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"{where}: limit on {name!r}: {side} = {value!r}; expected a finite number or None")
    return float(value)


def parse_limit(text: str) -> tuple[str, tuple[float | None, float | None]]:
    """One limit written as on the command line: ``"t_rms<=3.0"``, ``"toggle_margin_deg>=20"`` or
    ``"10<=t_max<=40"``.

    Returns
    -------
    (name, (lower, upper))
        Either bound None.

    Raises
    ------
    InputError
        Anything else.
    """
    expected = "expected 'name<=value', 'name>=value' or 'low<=name<=high'"
    parts = [p.strip() for p in str(text).replace(" ", "").split("<=")]
    found: tuple[str, tuple[float | None, float | None]] | None = None
    try:
        if len(parts) == 3:
            found = parts[1], (float(parts[0]), float(parts[2]))
        elif len(parts) == 2:
            found = parts[0], (None, float(parts[1]))
        else:
            ge = [p.strip() for p in str(text).replace(" ", "").split(">=")]
            if len(ge) == 2:
                found = ge[0], (float(ge[1]), None)
    except ValueError:
        found = None
    if found is not None and found[0].isidentifier():
        return found
    raise InputError(f"limit {text!r}: {expected}")


class DeclaredObjectives:
    """What a design problem declares it trades off, parsed: its objectives and its limits on simulated outputs.

    A base of :class:`~mechopt.optimize.problem.DesignProblem`, which sets ``name``, ``outputs``, ``objective`` and
    ``limits``; parsing raises the one-line :class:`~mechopt.errors.InputError` of a bad declaration.
    """

    name: str
    outputs: tuple[str, ...]
    objective: str | tuple[str, ...]
    limits: dict[str, tuple[float | None, float | None]]

    @property
    def objective_spec(self) -> ObjectiveSpec:
        """The objectives parsed: output names and senses (:func:`parse_objective`)."""
        return parse_objective(self.objective, self.outputs, f"problem {self.name!r}")

    @property
    def limit_spec(self) -> Limits:
        """The limits parsed (:meth:`Limits.parse`)."""
        return Limits.parse(self.limits, self.outputs, f"problem {self.name!r}")

    @property
    def trade_off(self) -> bool:
        """Several objectives or limits on simulated outputs: the method must see every output it reads."""
        return self.objective_spec.k > 1 or self.limit_spec.m > 0
