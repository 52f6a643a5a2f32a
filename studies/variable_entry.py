"""One entry of a study file's ``[variables]``: bounds, and the kind of a discrete variable.

::

    [variables]
    ab = [60.0, 130.0]                                   # continuous
    bc = { bounds = [250, 350], step = 0.1 }             # a drawing's resolution: 250.0, 250.1, ..., 350.0
    n = { bounds = [3, 12], integer = true }             # a count: 3, 4, ..., 12
    d = { values = [0.5, 0.63, 0.8, 1.0] }               # a catalogue; its bounds are its first and last values
    w = { lower = 10.0, upper = 40.0, unit = "mm", label = "w" }

Each is checked by :class:`~mechopt.optimize.variable.Variable` (a step that does not divide the range, an unsorted
or repeated catalogue, a catalogue of one value, non-integer bounds of an integer) and any error is one line that
names the file and the key.
"""

from __future__ import annotations

from typing import Any

from mechopt.errors import InputError, StudyError
from mechopt.optimize.variable import Variable
from mechopt.studies.study_file import StudyFile

__all__ = ["VARIABLE_KEYS", "study_variable"]

#: Keys of a variable written as a table.
VARIABLE_KEYS = ("bounds", "lower", "upper", "unit", "label", "step", "integer", "values")


def study_variable(study: StudyFile, name: str, value: Any, unit: str = "", label: str = "",
                   keys: tuple[str, ...] = VARIABLE_KEYS) -> Variable:
    """The variable ``name`` of ``[variables]``: ``[lower, upper]`` or a table of :data:`VARIABLE_KEYS`.

    Parameters
    ----------
    study : StudyFile
        The parsed study file (for messages).
    name : str
        The variable's name.
    value : list or dict
        Its entry.
    unit, label : str
        Defaults of the unit and the label (a mechanism's own variables have them).
    keys : tuple of str
        The keys this study accepts in a table (a mechanism's lengths take no ``unit``).

    Raises
    ------
    StudyError
        One line naming the file and the key: an unknown key, bounds given twice or not at all, a bad kind.
    """
    where = f"variables.{name}"
    if isinstance(value, list):
        lower, upper = study.numbers({name: value}, name, "variables", length=2)
        return _checked(study, where, dict(name=name, lower=lower, upper=upper, unit=unit, label=label))
    if not isinstance(value, dict):
        raise StudyError(f"{study.where}: key {where} = {value!r} must be [lower, upper] or a table such as "
                         "{ bounds = [60, 130], step = 0.1 }")
    unknown = sorted(set(value) - set(keys))
    if unknown:
        raise StudyError(f"{study.where}: unknown key {where}.{unknown[0]}; expected one of {list(keys)}")
    spec: dict[str, Any] = dict(name=name, unit=study.string(value, "unit", where, unit),
                                label=study.string(value, "label", where, label))
    if "bounds" in value:
        if "lower" in value or "upper" in value:
            raise StudyError(f"{study.where}: key {where} gives bounds and lower/upper; expected one of them")
        spec["lower"], spec["upper"] = study.numbers(value, "bounds", where, length=2)
    elif "lower" in value or "upper" in value:
        spec["lower"], spec["upper"] = study.number(value, "lower", where), study.number(value, "upper", where)
    elif "values" not in value:
        raise StudyError(f"{study.where}: key {where} has no bounds; expected bounds = [lower, upper] or values = "
                         "[...]")
    if "step" in value:
        spec["step"] = study.number(value, "step", where)
    if "integer" in value:
        if not isinstance(value["integer"], bool):
            raise StudyError(f"{study.where}: key {where}.integer = {value['integer']!r} must be true or false")
        spec["integer"] = value["integer"]
    if "values" in value:
        spec["values"] = tuple(study.numbers(value, "values", where))
    return _checked(study, where, spec)


def _checked(study: StudyFile, where: str, spec: dict[str, Any]) -> Variable:
    try:
        return Variable(**spec)
    except InputError as exc:
        raise StudyError(f"{study.where}: key {where}: {exc}") from None
