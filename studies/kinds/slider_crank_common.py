"""Helpers shared by the slider-crank studies' factories: bounds from ``[variables]``, one-line errors."""

from __future__ import annotations

from typing import Any

from mechopt.errors import InputError, StudyError
from mechopt.optimize.problem import Variable
from mechopt.studies.study_file import StudyFile

#: Values of the CLI's ``engine`` option these closed-form studies accept (None: not given).
CLOSED_FORM_ENGINES = (None, "analytic", "closed-form")


def variables_from_study(study: StudyFile, declared: tuple[tuple[str, str, str], ...],
                         defaults: dict[str, tuple[float, float]]) -> tuple[Variable, ...]:
    """The study's variables with bounds from ``[variables]`` (``name = [lower, upper]``), else the defaults.

    Parameters
    ----------
    study : StudyFile
        The parsed study file.
    declared : tuple of (name, unit, label)
        The plug-in's variables, in order.
    defaults : dict
        Bounds used when ``[variables]`` does not give them.

    Raises
    ------
    StudyError
        An unknown variable, bounds that are not two numbers or not increasing.
    """
    names = [d[0] for d in declared]
    section = study.table("variables", allowed=names, required=False)
    out = []
    for name, unit, label in declared:
        lower, upper = study.numbers(section, name, "variables", length=2, default=list(defaults[name]))
        try:
            out.append(Variable(name, lower, upper, unit, label))
        except InputError as exc:
            raise StudyError(f"{study.where}: {exc}") from None
    return tuple(out)


def check_options(study: StudyFile, options: dict[str, Any]) -> None:
    """Refuse an engine these closed-form studies do not have (one line)."""
    engine = (options or {}).get("engine")
    if engine not in CLOSED_FORM_ENGINES:
        raise StudyError(f"{study.where}: engine {engine!r}: this study is closed-form kinematics; "
                         "expected no engine or 'analytic'")
