"""``kind = "external"``: a study with no mechanism plug-in, only design variables and a user's simulator.

::

    kind = "external"

    [variables]
    width = { lower = 10.0, upper = 40.0, unit = "mm", label = "w" }
    angle = [0.0, 1.5]                    # bounds only: no unit
    teeth = { bounds = [12, 40], integer = true }
    wire = { values = [0.5, 0.63, 0.8, 1.0], unit = "mm" }   # a catalogue (also: step = 0.1 for a drawing grid)

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
from mechopt.studies.variable_entry import study_variable

__all__ = ["VariablesProblem", "problem_from_study"]

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
    variables = tuple(study_variable(study, name, value) for name, value in table.items())
    return VariablesProblem(str(study.config.get("name", study.path.parent.name)), variables)
