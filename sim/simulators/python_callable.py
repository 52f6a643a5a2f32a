"""A Python function as the simulator: ``"package.module:function"``, a dict of the design in, a dict of outputs out.

The function is imported in the worker process that calls it, on first use, with the study file's folder put on
``sys.path`` there (so ``my_sim:run`` finds ``my_sim.py`` beside the study file); mechopt's own process imports
nothing at load time, it only locates the module file to hash it into the fingerprint.  An exception of the function
is a recorded failure of that design with its one-line message; a missing or non-finite output too; the function
may raise :class:`~mechopt.errors.InfeasibleDesignError` or return ``{"infeasible": "reason"}``.
"""

from __future__ import annotations

import importlib
import importlib.machinery
import importlib.util
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from mechopt.errors import StudyError
from mechopt.sim.simulators.outputs import SimulatorFailure, checked_outputs, file_digest

__all__ = ["CallableSimulator", "module_file", "split_target"]

# Functions already imported in this process, by (target, folder).
_LOADED: dict[tuple[str, str], Callable[..., Any]] = {}


def split_target(target: str) -> tuple[str, str]:
    """``"package.module:function"`` -> (``"package.module"``, ``"function"``).

    Raises
    ------
    StudyError
        Not of that form.
    """
    module, sep, attr = target.partition(":")
    ok = sep and all(p.isidentifier() for p in module.split(".")) and all(p.isidentifier() for p in attr.split("."))
    if not ok:
        raise StudyError(f"simulator callable {target!r}: expected 'package.module:function'")
    return module, attr


def module_file(module: str, folder: str) -> str | None:
    """The file of ``module`` as it will be imported with ``folder`` first on ``sys.path``, without importing it.

    Returns
    -------
    str or None
        The source (or extension) file; None for a built-in module or one that is not found.
    """
    parts = module.split(".")
    spec = importlib.machinery.PathFinder.find_spec(parts[0], [folder, *sys.path])
    if spec is None:
        try:
            spec = importlib.util.find_spec(parts[0])
        except (ImportError, ValueError):
            return None
    for i in range(1, len(parts)):
        locations = None if spec is None else spec.submodule_search_locations
        if not locations:
            return None
        spec = importlib.machinery.PathFinder.find_spec(".".join(parts[: i + 1]), list(locations))
    if spec is None or not spec.has_location:
        return None
    return spec.origin


def _load(target: str, folder: str) -> Callable[..., Any]:
    key = (target, folder)
    if key not in _LOADED:
        module_name, attr = split_target(target)
        if folder not in sys.path:
            sys.path.insert(0, folder)
        obj: Any = importlib.import_module(module_name)
        for part in attr.split("."):
            try:
                obj = getattr(obj, part)
            except AttributeError:
                raise SimulatorFailure(f"module {module_name} has no {attr!r}") from None
        if not callable(obj):
            raise SimulatorFailure(f"{target} is a {type(obj).__name__}, not a function")
        _LOADED[key] = obj
    return _LOADED[key]


@dataclass(frozen=True)
class CallableSimulator:
    """Call a Python function once per design.

    Parameters
    ----------
    target : str
        ``"package.module:function"``; the function takes ``{name: value}`` (the variables' units) and returns a dict
        with every declared output.
    outputs : tuple of str
        The outputs it must return (finite numbers).
    folder : str
        The study file's folder (absolute), put first on ``sys.path`` in the worker before the import.
    """

    target: str
    outputs: tuple[str, ...]
    folder: str

    def settings(self) -> dict[str, Any]:
        """The target and the SHA-256 of its module's file (editing the function invalidates stored samples)."""
        path = module_file(split_target(self.target)[0], self.folder)
        return {"callable": self.target, "module_sha256": file_digest(path) if path else None}

    def run(self, design: Mapping[str, float], units: Mapping[str, str] | None = None) -> dict[str, Any]:
        """Simulate one design (``units`` is accepted for symmetry with the command and not passed on).

        Returns
        -------
        dict
            Every declared output as a float, plus whatever else the function returned.

        Raises
        ------
        InfeasibleDesignError
            Raised by the function, or ``{"infeasible": reason}`` returned.
        SimulatorFailure
            An unusable return value (the message names the key); the function's own exceptions pass through.
        """
        fn = _load(self.target, self.folder)
        return checked_outputs(fn({k: float(v) for k, v in design.items()}), self.outputs)
