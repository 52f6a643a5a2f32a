"""Declared options, in the manner of SMT's ``OptionsDictionary``: each option is declared once with its default,
type, allowed values or range and a description; checking and help text come from the declaration."""

from __future__ import annotations

import collections.abc
import inspect
import math
import re
import types
import typing
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from mechopt.errors import InputError

__all__ = ["Option", "Options", "options_of"]


@dataclass(frozen=True)
class Option:
    """One declared option.

    Parameters
    ----------
    name : str
        Its name (a TOML key, a keyword argument).
    default : object
        Value when not given.
    types : type or tuple of types
        Accepted types (``float`` accepts integers too; ``bool`` is never taken for a number).
    desc : str
        One line for help texts, with the unit.
    values : tuple, optional
        The allowed values.
    minimum, maximum : float, optional
        Inclusive range of a number.
    nullable : bool
        Whether None is accepted.
    """

    name: str
    default: Any
    types: type | tuple[type, ...]
    desc: str
    values: tuple | None = None
    minimum: float | None = None
    maximum: float | None = None
    nullable: bool = False

    def check(self, value: Any, where: str) -> Any:
        """The value, converted (int -> float where a float is declared), or a one-line InputError."""
        if value is None and self.nullable:
            return None
        types = self.types if isinstance(self.types, tuple) else (self.types,)
        if float in types and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        is_bool = isinstance(value, bool)
        if not isinstance(value, types) or (is_bool and bool not in types):
            names = " or ".join(t.__name__ for t in types)
            raise InputError(f"{where}{self.name} = {value!r}: expected {names} ({self.desc})")
        if isinstance(value, float) and not math.isfinite(value):
            raise InputError(f"{where}{self.name} = {value!r}: expected a finite number")
        if self.values is not None and value not in self.values:
            raise InputError(f"{where}{self.name} = {value!r}; expected one of {', '.join(map(str, self.values))}")
        if self.minimum is not None and not is_bool and isinstance(value, int | float) and value < self.minimum:
            raise InputError(f"{where}{self.name} = {value!r}: expected >= {self.minimum:g} ({self.desc})")
        if self.maximum is not None and not is_bool and isinstance(value, int | float) and value > self.maximum:
            raise InputError(f"{where}{self.name} = {value!r}: expected <= {self.maximum:g} ({self.desc})")
        return value


class Options:
    """A set of declared options with checked values; read them as attributes.

    Subclasses list their :class:`Option` declarations in ``DECLARED``.

    Parameters
    ----------
    values : mapping, optional
        Values by name; unknown names and ill-typed values are one-line errors.
    where : str
        Prefix of error messages (``"surrogate."`` for a study file's section).
    """

    DECLARED: tuple[Option, ...] = ()

    def __init__(self, values: Mapping[str, Any] | None = None, where: str = "", **kwargs: Any) -> None:
        declared = {o.name: o for o in self.DECLARED}
        merged = {**(values or {}), **kwargs}
        unknown = sorted(set(merged) - set(declared))
        if unknown:
            raise InputError(f"unknown option {where}{unknown[0]}; expected one of {', '.join(sorted(declared))}")
        self._values = {name: opt.default for name, opt in declared.items()}
        for name, value in merged.items():
            self._values[name] = declared[name].check(value, where)

    def __getattr__(self, name: str) -> Any:
        values = self.__dict__.get("_values")
        if values is None or name not in values:
            raise AttributeError(name)
        return values[name]

    def replace(self, **changes: Any) -> Options:
        """A copy with some values changed (checked)."""
        return type(self)({**self._values, **changes})

    def to_dict(self) -> dict[str, Any]:
        """All values by name."""
        return dict(self._values)

    @classmethod
    def help(cls) -> str:
        """One line per declared option: name, default, description."""
        return "\n".join(f"{o.name} (default {o.default!r}): {o.desc}" for o in cls.DECLARED)

    @classmethod
    def names(cls) -> Iterable[str]:
        """Declared names."""
        return [o.name for o in cls.DECLARED]

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._values})"


def _option_types(hint: Any) -> tuple[tuple[type, ...], bool]:
    """The runtime types of a type hint (``int | None``, ``tuple[float, float]``, ``Sequence[float]``) and whether
    None is accepted."""
    args = typing.get_args(hint) if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union \
        else (hint,)
    found: list[type] = []
    for arg in args:
        origin = typing.get_origin(arg) or arg
        if origin is collections.abc.Sequence:
            found.extend((tuple, list))
        elif isinstance(origin, type) and origin is not type(None):
            found.append(origin)
    return tuple(found) or (object,), type(None) in args


def _parameter_texts(doc: str) -> dict[str, str]:
    """Each parameter's description in a (dedented) numpydoc docstring, its first sentence, by name; grouped names
    (``fd_step, ftol, maxiter``) share theirs."""
    section = re.split(r"^Parameters\n-+\n", doc, maxsplit=1, flags=re.M)
    if len(section) < 2:
        return {}
    texts: dict[str, str] = {}
    names: list[str] = []
    for line in re.split(r"^\w+\n-+\n", section[1], maxsplit=1, flags=re.M)[0].splitlines():
        head = re.fullmatch(r"([A-Za-z_][\w, ]*?)\s*(?::\s*(.*))?", line)
        if head:
            names = [n.strip() for n in head.group(1).split(",")]
            see = head.group(2) or ""
            texts.update({name: see if see.startswith("see ") else "" for name in names})
        elif line.startswith("    ") and names:
            texts.update({name: f"{texts[name]} {line.strip()}".strip() for name in names})
    # The first sentence: a full stop before a capital, not one of an abbreviation ("et al.", "Eq.").
    return {name: re.split(r"(?<! al)(?<! Eq)\.\s+(?=[A-Z])", text)[0].rstrip(".") for name, text in texts.items()}


def options_of(fn: Callable[..., Any]) -> tuple[Option, ...]:
    """The options a function declares by its keyword-only parameters: default, type hint and the description of
    its docstring's Parameters section.

    Parameters
    ----------
    fn : callable
        ``f(problem, seed, *, name=default, ...)``; a ``**kwargs`` catch-all declares nothing.

    Returns
    -------
    tuple of Option
        In the signature's order.
    """
    hints = typing.get_type_hints(fn)
    texts = _parameter_texts(inspect.getdoc(fn) or "")
    declared = []
    for p in inspect.signature(fn).parameters.values():
        if p.kind is not inspect.Parameter.KEYWORD_ONLY:
            continue
        kinds, nullable = _option_types(hints.get(p.name, object))
        declared.append(Option(p.name, p.default, kinds, texts.get(p.name) or "see the function's docstring",
                               nullable=nullable or p.default is None))
    return tuple(declared)
