"""``kind = "external"``: a study with no mechanism plug-in, only design variables and a user's simulator.

::

    kind = "external"

    [variables]
    width = { lower = 10.0, upper = 40.0, unit = "mm", label = "w" }
    angle = [0.0, 1.5]                    # bounds only: no unit

    [simulator]
    command = ["{python}", "my_sim.py"]
    outputs = ["cost"]

There are no constraints beyond the bounds: a design the simulator cannot handle is reported by it as
``{"infeasible": "reason"}`` (treated as infeasible, NaN for the model).  Constraints that can be computed cheaply
from the variables belong in a mechanism plug-in (a :class:`~mechopt.optimize.problem.DesignProblem` with
``margins``), which can be combined with ``[simulator]`` the same way.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mechopt.errors import StudyError
from mechopt.optimize.problem import DesignProblem, Variable
from mechopt.studies.study_file import StudyFile

__all__ = ["VariablesProblem", "problem_from_study"]

_VARIABLE_KEYS = ("lower", "upper", "unit", "label")


class VariablesProblem(DesignProblem):
    """Design variables and nothing else: the ``[simulator]`` of the study supplies the evaluator.

    Parameters
    ----------
    name : str
        Name of the study.
    variables : tuple of Variable
        The design variables with their bounds and units.
    """

    def __init__(self, name: str, variables: tuple[Variable, ...]) -> None:
        self.name = name
        self.variables = tuple(variables)

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        """Not available: a study of kind "external" is evaluated by its ``[simulator]``."""
        raise StudyError(f"study {self.name!r} of kind \"external\" has no evaluator of its own: add a [simulator]")


def _variable(study: StudyFile, name: str, value: Any) -> Variable:
    where = f"variables.{name}"
    if isinstance(value, list):
        lower, upper = study.numbers({name: value}, name, "variables", length=2)
        unit, label = "", ""
    elif isinstance(value, dict):
        unknown = sorted(set(value) - set(_VARIABLE_KEYS))
        if unknown:
            raise StudyError(f"{study.where}: unknown key {where}.{unknown[0]}; expected one of {list(_VARIABLE_KEYS)}")
        lower = study.number(value, "lower", where)
        upper = study.number(value, "upper", where)
        unit = study.string(value, "unit", where, "")
        label = study.string(value, "label", where, "")
    else:
        raise StudyError(f"{study.where}: key {where} = {value!r} must be [lower, upper] or "
                         "{ lower = .., upper = .., unit = \"mm\" }")
    if not name.isidentifier():
        raise StudyError(f"{study.where}: variable name {name!r} must be an identifier such as 'width'")
    if not lower < upper:
        raise StudyError(f"{study.where}: key {where}: bounds [{lower}, {upper}] must satisfy lower < upper")
    return Variable(name, lower, upper, unit, label)


def problem_from_study(study: StudyFile, options: dict[str, Any]) -> VariablesProblem:
    """The variables of a study of kind ``"external"`` (the engine then applies its ``[simulator]``).

    Parameters
    ----------
    study : StudyFile
        The parsed study file.
    options : dict
        Command-line overrides; ``engine`` has no meaning here and is ignored.

    Raises
    ------
    StudyError
        No ``[simulator]`` section, no variables, or a malformed variable.
    """
    study.table("simulator")  # raises "missing section [simulator]"
    table = study.table("variables")
    if not table:
        raise StudyError(f"{study.where}: section [variables] declares no variable")
    variables = tuple(_variable(study, name, value) for name, value in table.items())
    return VariablesProblem(str(study.config.get("name", study.path.parent.name)), variables)
