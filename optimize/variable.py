"""A design variable: continuous, on a drawing grid, an integer, or a value from a catalogue.

A workshop builds lengths to a drawing's resolution (``step=0.1`` mm), counts teeth and coils in integers
(``integer=True``) and takes wire, tubes and motors from a catalogue (``values=(0.5, 0.63, 0.8, 1.0)``).  A discrete
variable's allowed values are ordered numbers, so every method may treat it as a continuous coordinate inside the
same bounds and round a proposal to the nearest allowed value (:meth:`Variable.snap`) before it is simulated: the
sample store keys the rounded design, so two proposals that round alike are one simulation.

The grid of ``step`` starts at ``lower`` and must end at ``upper``: a step that does not divide the range is
refused with the two ranges that it would divide, rather than silently moving a bound the user wrote.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.runs.sample_record import KEY_DECIMALS

__all__ = ["MIN_SPAN", "Variable"]

#: Narrowest range of a continuous variable, in its unit: a thousand steps of the sample store's resolution.
MIN_SPAN = 10.0 ** (3 - KEY_DECIMALS)

#: Relative slack with which a step must divide the range (the float error of ``(upper - lower) / step``).
_DIVIDES = 1e-9


def _finite(name: str, key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating) \
            or not math.isfinite(value):
        raise InputError(f"variable {name}: {key} = {value!r} must be a finite number")
    return float(value)


@dataclass(frozen=True)
class Variable:
    """One design variable.

    Parameters
    ----------
    name : str
        Identifier used everywhere a user sees a design (CLI, result.json, reports, axis labels), e.g. ``"oa"``.
    lower, upper : float
        Bounds of the region of interest, in ``unit``.  With ``values`` they may be omitted (they are the
        catalogue's first and last values).
    unit : str
        Unit of the variable (``"mm"``, ``"rad"``, ``""`` for a ratio).
    label : str
        Symbol for plots and tables (``"|OA|"``); default the name.
    step : float, optional
        Resolution of a drawing, in ``unit``: the allowed values are ``lower + k * step`` up to ``upper``, which
        the step must divide.
    integer : bool, default False
        Only whole numbers between integer bounds (teeth, coils, a count of parts).
    values : sequence of float, optional
        A catalogue: the allowed values, increasing, at least two (wire diameters, a motor's rated torques).

    Examples
    --------
    >>> Variable("ab", 60.0, 130.0, "mm", step=0.1).count
    701
    >>> Variable("d", unit="mm", values=(0.5, 0.63, 0.8, 1.0)).snap(np.array([0.7, 0.9]))
    array([0.63, 0.8 ])
    """

    name: str
    lower: float | None = None
    upper: float | None = None
    unit: str = ""
    label: str = ""
    step: float | None = None
    integer: bool = False
    values: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise InputError(f"variable name {self.name!r}: expected an identifier such as 'oa'")
        kinds = [k for k, on in (("step", self.step is not None), ("integer", bool(self.integer)),
                                 ("values", self.values is not None)) if on]
        if len(kinds) > 1:
            raise InputError(f"variable {self.name}: {' and '.join(kinds)} given together; expected at most one of "
                             "step, integer=True and values")
        if self.values is not None:
            self._set_catalogue()
        for key in ("lower", "upper"):
            object.__setattr__(self, key, _finite(self.name, key, getattr(self, key)))
        if not self.lower < self.upper:
            raise InputError(f"variable {self.name}: bounds [{self.lower}, {self.upper}] must satisfy lower < upper")
        if self.integer:
            self._check_integer()
        elif self.step is not None:
            self._check_step()
        elif self.values is None and round(self.upper - self.lower, KEY_DECIMALS) < MIN_SPAN:
            # The sample store tells designs apart to KEY_DECIMALS decimals: a narrower range would hold too few
            # distinct designs, and a method's steps would land on designs it has already simulated.
            raise InputError(f"variable {self.name}: bounds [{self.lower!r}, {self.upper!r}] span "
                             f"{self.upper - self.lower:.3g}, expected at least {MIN_SPAN:g} {self.unit} (the sample "
                             f"store resolves {10.0**-KEY_DECIMALS:g}): state the variable in a smaller unit")

    def _set_catalogue(self) -> None:
        name = self.name
        if isinstance(self.values, str | bytes) or not isinstance(self.values, Sequence | np.ndarray):
            raise InputError(f"variable {name}: values = {self.values!r:.80}; expected a list of numbers")
        vals = tuple(_finite(name, "a catalogue value", v) for v in self.values)
        if len(vals) < 2:
            raise InputError(f"variable {name}: a catalogue of {len(vals)} value {list(vals)} is a constant, "
                             "expected at least two values (fix a constant in the simulator instead)")
        rounded = [round(v, KEY_DECIMALS) for v in vals]
        if len(set(rounded)) != len(rounded):
            dup = sorted({v for v in rounded if rounded.count(v) > 1})
            raise InputError(f"variable {name}: values {list(vals)} repeat {dup}; expected distinct values")
        if any(b <= a for a, b in zip(vals, vals[1:], strict=False)):
            raise InputError(f"variable {name}: values {list(vals)} are not increasing; expected them sorted, "
                             f"e.g. {sorted(vals)}")
        for key, end in (("lower", vals[0]), ("upper", vals[-1])):
            given = getattr(self, key)
            if given is not None and not math.isclose(float(given), end, rel_tol=1e-12, abs_tol=1e-12):
                raise InputError(f"variable {name}: {key} = {given!r} but the catalogue's {key} value is {end!r}; "
                                 "expected no bounds with values (they follow from the catalogue)")
        object.__setattr__(self, "values", vals)
        object.__setattr__(self, "lower", vals[0])
        object.__setattr__(self, "upper", vals[-1])

    def _check_integer(self) -> None:
        for key in ("lower", "upper"):
            value = getattr(self, key)
            if value != round(value):
                raise InputError(f"variable {self.name}: integer=True with {key} = {value!r}; expected whole-number "
                                 "bounds")
        object.__setattr__(self, "integer", True)

    def _check_step(self) -> None:
        step = _finite(self.name, "step", self.step)
        if step <= 0.0 or round(step, KEY_DECIMALS) == 0.0:
            raise InputError(f"variable {self.name}: step = {self.step!r}; expected a positive step of at least "
                             f"{10.0**-KEY_DECIMALS:g} {self.unit}")
        n = (self.upper - self.lower) / step
        if abs(n - round(n)) > _DIVIDES * max(1.0, n):
            k = math.floor(n)
            below, above = self.lower + k * step, self.lower + (k + 1) * step
            raise InputError(f"variable {self.name}: step {step:g} does not divide [{self.lower:g}, {self.upper:g}] "
                             f"(the grid starts at lower); expected upper = {below:.10g} or {above:.10g}")
        object.__setattr__(self, "step", step)

    # --- what the methods read ----------------------------------------------------------------------------------

    @property
    def discrete(self) -> bool:
        """Whether only some values of the bounds are allowed (a grid, an integer, a catalogue)."""
        return self.integer or self.step is not None or self.values is not None

    @property
    def kind(self) -> str:
        """``"continuous"``, ``"grid"``, ``"integer"`` or ``"catalogue"`` (plans and reports)."""
        if self.values is not None:
            return "catalogue"
        if self.integer:
            return "integer"
        return "grid" if self.step is not None else "continuous"

    @property
    def resolution(self) -> float:
        """Distance between neighbouring allowed values (the smallest one of a catalogue); 0 when continuous."""
        if self.values is not None:
            return float(np.min(np.diff(self.values)))
        if self.integer:
            return 1.0
        return float(self.step) if self.step is not None else 0.0

    @property
    def count(self) -> int | None:
        """Number of allowed values, None when continuous."""
        if self.values is not None:
            return len(self.values)
        if self.integer:
            return int(round(self.upper - self.lower)) + 1
        if self.step is not None:
            return int(round((self.upper - self.lower) / self.step)) + 1
        return None

    def allowed(self) -> np.ndarray:
        """Every allowed value, increasing (a discrete variable only).

        Raises
        ------
        InputError
            When the variable is continuous.
        """
        if self.values is not None:
            return np.array(self.values, dtype=float)
        if not self.discrete:
            raise InputError(f"variable {self.name} is continuous: it has no list of allowed values")
        step = 1.0 if self.integer else float(self.step)
        return np.round(self.lower + step * np.arange(self.count), KEY_DECIMALS)

    def snap(self, v: Any, clip: bool = True) -> np.ndarray:
        """The allowed value nearest to each value (clipped to the bounds first); continuous: only clipped.

        Parameters
        ----------
        v : array_like
            Values in ``unit``.
        clip : bool, default True
            False: a value beyond a bound goes to the nearest value of the grid (or the integers) continued past
            the bound, and a continuous value stays as it is (a line model's samples beyond the box stay apart);
            a catalogue is always clipped.

        Returns
        -------
        ndarray
            Same shape, every value allowed (rounded to the store's resolution, so equal designs compare equal).
        """
        v = np.asarray(v, dtype=float)
        if clip or self.values is not None:
            v = np.clip(v, self.lower, self.upper)
        if self.values is not None:
            cat = np.asarray(self.values)
            i = np.clip(np.searchsorted(cat, v), 1, len(cat) - 1)
            return np.where(v - cat[i - 1] <= cat[i] - v, cat[i - 1], cat[i])
        if not self.discrete:
            return v
        step = 1.0 if self.integer else float(self.step)
        k = np.floor((v - self.lower) / step + 0.5)
        k = np.clip(k, 0, self.count - 1) if clip else k
        return np.round(self.lower + k * step, KEY_DECIMALS)

    def neighbours(self, value: float) -> np.ndarray:
        """The allowed values just below and above ``value``'s snapped value (those inside the bounds)."""
        if not self.discrete:
            raise InputError(f"variable {self.name} is continuous: it has no neighbouring values")
        here = float(self.snap(value))
        if self.values is not None:
            cat = np.asarray(self.values)
            i = int(np.searchsorted(cat, here))
            return cat[[j for j in (i - 1, i + 1) if 0 <= j < len(cat)]]
        out = self.snap(np.array([here - self.resolution, here + self.resolution]))
        return out[out != here]

    def describe_kind(self) -> str:
        """``step 0.1 mm``, ``integer``, ``catalogue of 4`` or ``continuous``, for plans and reports."""
        if self.values is not None:
            return f"catalogue of {len(self.values)}"
        if self.integer:
            return "integer"
        if self.step is not None:
            return f"step {self.step:g}{(' ' + self.unit) if self.unit else ''}"
        return "continuous"

    @property
    def axis_label(self) -> str:
        """``label (unit)`` for a plot axis."""
        text = self.label or self.name
        return f"{text} ({self.unit})" if self.unit else text
