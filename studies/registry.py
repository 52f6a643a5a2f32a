"""Mechanism plug-ins, found by the ``kind`` of a study file.

A plug-in is a function ``problem_from_study(study: StudyFile, options: dict) -> DesignProblem``.  The kinds shipped
with mechopt are listed in :data:`MECHANISMS` as ``"module:function"`` strings (imported only when used); other
packages add theirs through the entry-point group ``mechopt.mechanisms`` or at run time with
:func:`register_mechanism`.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from importlib.metadata import entry_points
from typing import Any

from mechopt.errors import StudyError

__all__ = ["MECHANISMS", "mechanism_factory", "mechanism_kinds", "register_mechanism"]

#: Built-in kinds -> "module:function" of their study-file reader.
MECHANISMS: dict[str, str] = {
    "four-bar": "mechopt.studies.kinds.four_bar:problem_from_study",
    "offset-crank-slider": "mechopt.studies.kinds.offset_crank_slider:problem_from_study",
    "rowing": "mechopt.studies.kinds.rowing:problem_from_study",
    "flexible-slider-crank": "mechopt.studies.kinds.flexible_slider_crank:problem_from_study",
    "flexible-four-bar": "mechopt.studies.kinds.flexible_four_bar:problem_from_study",
    "path-synthesis": "mechopt.studies.kinds.path_synthesis:problem_from_study",
    "external": "mechopt.studies.kinds.external:problem_from_study",
}

_REGISTERED: dict[str, Callable[..., Any]] = {}


def register_mechanism(kind: str, factory: Callable[..., Any]) -> None:
    """Make ``kind`` available to study files (``factory(study, options) -> DesignProblem``)."""
    if not isinstance(kind, str) or not kind:
        raise StudyError(f"mechanism kind {kind!r}: expected a non-empty string")
    _REGISTERED[kind] = factory


def mechanism_kinds() -> list[str]:
    """Every kind a study file may name."""
    plugins = {ep.name for ep in entry_points(group="mechopt.mechanisms")}
    return sorted(set(MECHANISMS) | set(_REGISTERED) | plugins)


def mechanism_factory(kind: str) -> Callable[..., Any]:
    """The study-file reader of ``kind``.

    Raises
    ------
    StudyError
        For an unknown kind, listing the known ones.
    """
    if kind in _REGISTERED:
        return _REGISTERED[kind]
    if kind in MECHANISMS:
        module, _, name = MECHANISMS[kind].partition(":")
        return getattr(importlib.import_module(module), name)
    for ep in entry_points(group="mechopt.mechanisms"):
        if ep.name == kind:
            return ep.load()
    raise StudyError(f"unknown mechanism kind {kind!r}; expected one of {', '.join(mechanism_kinds())}")
