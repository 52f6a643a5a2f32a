"""One evaluated design as the store keeps it, and the canonical key that identifies its design.

Designs are identified by a canonical text key, the values rounded to 1e-9 in the variables' units, so that float
noise (``0.1 + 0.2`` vs ``0.3``) does not create duplicates.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any

from mechopt.errors import InputError

__all__ = ["KEY_DECIMALS", "STATUSES", "SampleRecord", "as_design", "design_key", "utc_timestamp"]

#: Decimal places of the canonical design key: 1e-9 (mm, rad...) is far below any manufacturing tolerance and far
#: above the float noise of values of a few hundred units (~1e-13).
KEY_DECIMALS = 9

#: Allowed values of :attr:`SampleRecord.status`.
STATUSES = ("ok", "infeasible", "failed")


def as_design(design: Sequence[float], dim: int | None = None) -> tuple[float, ...]:
    """Validate a design and return it as a tuple of floats.

    Parameters
    ----------
    design : sequence of float
        The design variables, in their units (mm, rad...).
    dim : int, optional
        Required number of values; any number >= 1 if omitted.

    Returns
    -------
    tuple of float

    Raises
    ------
    InputError
        If the design is not a non-empty sequence of finite numbers (of length ``dim`` when given).
    """
    try:
        values = tuple(float(x) for x in design)
    except (TypeError, ValueError) as exc:
        raise InputError(f"a design must be a sequence of numbers, got {design!r:.80}") from exc
    if not values:
        raise InputError("a design must have at least one value, got none")
    if dim is not None and len(values) != dim:
        raise InputError(f"a design must have {dim} values, got {len(values)}: {values!r:.80}")
    if not all(math.isfinite(x) for x in values):
        raise InputError(f"a design must have finite values, got {values!r:.80}")
    return values


def design_key(design: Sequence[float]) -> str:
    """Canonical text key of a design, insensitive to float noise below 1e-9.

    Parameters
    ----------
    design : sequence of float
        Any number d >= 1 of values, in the variables' units.

    Returns
    -------
    str
        The values with :data:`KEY_DECIMALS` decimals, comma-separated, e.g. ``"100.000000000,250.000000000"``.

    Raises
    ------
    InputError
        If the design is not a non-empty sequence of finite numbers.
    """
    # ``+ 0.0`` turns -0.0 into 0.0 so that both print the same.
    return ",".join(f"{x + 0.0:.{KEY_DECIMALS}f}" for x in as_design(design))


def utc_timestamp() -> str:
    """Now as an ISO 8601 UTC timestamp with milliseconds, e.g. ``2026-01-31T12:00:00.123Z`` (sorts as text)."""
    return datetime.now(UTC).isoformat(timespec="milliseconds").replace("+00:00", "Z")


@dataclass(frozen=True)
class SampleRecord:
    """One evaluated design.

    Attributes
    ----------
    design : tuple of float
        The design as first requested, in the variables' units (float noise below 1e-9 maps to the same
        :attr:`key`).
    fingerprint : str
        Hash of the problem and settings the design was evaluated with (``DesignProblem.fingerprint()``).
    status : str
        ``"ok"``, ``"infeasible"`` (the evaluator raised ``InfeasibleDesignError``) or ``"failed"`` (any other
        error, or an unusable return value).
    outputs : dict
        Everything the evaluator returned (JSON values); empty unless ``status == "ok"``.
    error : str or None
        One-line message for ``infeasible`` and ``failed`` records.
    wall_time_s : float or None
        Wall time of the evaluator call in s, measured in the worker.
    timestamp : str
        ISO 8601 UTC time when the result was known.
    """

    design: tuple[float, ...]
    fingerprint: str
    status: str
    outputs: dict[str, Any] = field(default_factory=dict)
    error: str | None = None
    wall_time_s: float | None = None
    timestamp: str = field(default_factory=utc_timestamp)

    def __post_init__(self) -> None:
        object.__setattr__(self, "design", as_design(self.design))
        if self.status not in STATUSES:
            raise InputError(f"status must be one of {', '.join(STATUSES)}, got {self.status!r}")
        if not isinstance(self.fingerprint, str) or not self.fingerprint:
            raise InputError(f"a record needs a fingerprint string, got {self.fingerprint!r}")
        if not isinstance(self.outputs, dict):
            raise InputError(f"outputs must be a dict, got {type(self.outputs).__name__}")
        if self.outputs and self.status != "ok":
            raise InputError(f"a {self.status!r} record has no outputs, got {sorted(self.outputs)}")

    @property
    def key(self) -> str:
        """Canonical key of the design (:func:`design_key`)."""
        return design_key(self.design)

    @property
    def ok(self) -> bool:
        """Whether the evaluation succeeded."""
        return self.status == "ok"

    def value(self, name: str) -> float:
        """One output as a float.

        Parameters
        ----------
        name : str
            Output name, e.g. ``"t_rms"``.

        Returns
        -------
        float
            The output, in the evaluator's unit; NaN unless the record is ``ok`` and has a numeric output ``name``.
        """
        if not self.ok:
            return math.nan
        value = self.outputs.get(name)
        if isinstance(value, bool) or not isinstance(value, int | float):
            return math.nan
        return float(value)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict of the record (for ``result.json`` and reports).

        Returns
        -------
        dict
            All attributes, the design as a list, plus ``key``.
        """
        return {
            "design": list(self.design),
            "key": self.key,
            "fingerprint": self.fingerprint,
            "status": self.status,
            "outputs": dict(self.outputs),
            "error": self.error,
            "wall_time_s": self.wall_time_s,
            "timestamp": self.timestamp,
        }
