"""A study file (TOML) as the mechanism plug-ins read it: typed keys, one-line errors, data files found.

Every key is checked: a missing, misspelt or ill-typed key is a one-line :class:`~mechopt.errors.StudyError` that
names the file, the key and what was expected.  Data files named by a study are looked up beside the TOML file, then
in the packaged study of the same name (so that a copied study file still finds its tables), and the error says
where it looked.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mechopt.errors import StudyError

__all__ = ["PACKAGED_STUDIES", "StudyFile"]

#: Folder of the studies shipped with mechopt (one sub-folder each, holding ``study.toml``).
PACKAGED_STUDIES = Path(__file__).resolve().parent


@dataclass(frozen=True)
class StudyFile:
    """The parsed TOML of a study, with readers that check types.

    Attributes
    ----------
    path : Path
        The TOML file.
    config : dict
        Its parsed content.
    packaged : str or None
        Name of the packaged study this file was copied from (its ``name``), where data files are also looked up.
    """

    path: Path
    config: dict[str, Any] = field(default_factory=dict)
    packaged: str | None = None
    #: Top-level sections read through :meth:`table` so far: the catalogue refuses a key nothing read (a misspelt
    #: section would otherwise be ignored, and its settings with it).
    read: set[str] = field(default_factory=set, compare=False, repr=False)

    @property
    def where(self) -> str:
        """The file's name, for messages."""
        return self.path.name

    def table(self, key: str, allowed: Iterable[str] | None = None, required: bool = True) -> dict[str, Any]:
        """Section ``[key]``; unknown keys in it are errors when ``allowed`` is given.

        Parameters
        ----------
        key : str
            Section name (dots for nested tables: ``"simulator.env"``).
        allowed : iterable of str, optional
            The keys the section may hold.
        required : bool
            Raise when the section is missing (else return ``{}``).
        """
        self.read.add(key.split(".")[0])
        value: Any = self.config
        for part in key.split("."):
            value = value.get(part) if isinstance(value, dict) else None
        if value is None:
            if required:
                raise StudyError(f"{self.where}: missing section [{key}]")
            return {}
        if not isinstance(value, dict):
            raise StudyError(f"{self.where}: key {key} must be a table [{key}]")
        if allowed is not None:
            allowed = set(allowed)
            unknown = sorted(set(value) - allowed)
            if unknown:
                raise StudyError(f"{self.where}: unknown key {key}.{unknown[0]}; expected one of {sorted(allowed)}")
        return value

    def number(self, section: dict[str, Any], key: str, where: str, default: float | None = None,
               positive: bool = False, minimum: float | None = None, maximum: float | None = None) -> float:
        """A finite number ``section[key]`` (``where`` names the section in messages, e.g. ``"mechanism"``)."""
        if key not in section:
            if default is None:
                raise StudyError(f"{self.where}: missing key {where}.{key}")
            return float(default)
        value = section[key]
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise StudyError(f"{self.where}: key {where}.{key} = {value!r} must be a finite number")
        if positive and value <= 0:
            raise StudyError(f"{self.where}: key {where}.{key} = {value!r} must be > 0")
        if minimum is not None and value < minimum:
            raise StudyError(f"{self.where}: key {where}.{key} = {value!r} must be >= {minimum}")
        if maximum is not None and value > maximum:
            raise StudyError(f"{self.where}: key {where}.{key} = {value!r} must be <= {maximum}")
        return float(value)

    def integer(self, section: dict[str, Any], key: str, where: str, default: int | None = None,
                minimum: int | None = None) -> int:
        """A whole number ``section[key]``."""
        if key not in section:
            if default is None:
                raise StudyError(f"{self.where}: missing key {where}.{key}")
            return int(default)
        value = section[key]
        if isinstance(value, bool) or not isinstance(value, int):
            raise StudyError(f"{self.where}: key {where}.{key} = {value!r} must be a whole number")
        if minimum is not None and value < minimum:
            raise StudyError(f"{self.where}: key {where}.{key} = {value!r} must be >= {minimum}")
        return int(value)

    def string(self, section: dict[str, Any], key: str, where: str, default: str | None = None,
               choices: Iterable[str] | None = None) -> str:
        """A string ``section[key]``, one of ``choices`` when given."""
        if key not in section:
            if default is None:
                raise StudyError(f"{self.where}: missing key {where}.{key}")
            return default
        value = section[key]
        if not isinstance(value, str):
            raise StudyError(f"{self.where}: key {where}.{key} = {value!r} must be a string")
        if choices is not None and value not in (choices := list(choices)):
            raise StudyError(f"{self.where}: key {where}.{key} = {value!r}; expected one of {', '.join(choices)}")
        return value

    def numbers(self, section: dict[str, Any], key: str, where: str, length: int | None = None,
                default: list[float] | None = None) -> list[float]:
        """A list of finite numbers ``section[key]`` (of ``length`` items when given)."""
        if key not in section:
            if default is None:
                raise StudyError(f"{self.where}: missing key {where}.{key}")
            return list(default)
        value = section[key]
        ok = isinstance(value, list) and all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value)
        if not ok or (length is not None and len(value) != length):
            size = f"{length} " if length is not None else ""
            raise StudyError(f"{self.where}: key {where}.{key} = {value!r} must be a list of {size}finite numbers")
        return [float(v) for v in value]

    def data_path(self, name: str, key: str) -> Path:
        """A data file named by key ``key``: beside the TOML file, else in the packaged study it was copied from.

        Raises
        ------
        StudyError
            Naming both places looked in.
        """
        here = (self.path.parent / name).resolve()
        if here.is_file():
            return here
        tried = [str(here)]
        if self.packaged:
            shipped = PACKAGED_STUDIES / self.packaged / name
            if shipped.is_file():
                return shipped
            tried.append(str(shipped))
        raise StudyError(f"{self.where}: key {key}: data file {name!r} not found (looked in {' and '.join(tried)}); "
                         "copy it beside the study file")
