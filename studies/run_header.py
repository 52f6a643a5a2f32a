"""The first lines of a study run: what is being optimised, in the user's words, not a Python repr.

Issue 25 read ``study my-ext: <ExternalProblem 'my-ext': x, y, z -> f>``; a user wants the study's description, its
variables with their bounds and units, the objective and the simulator that will run.
"""

from __future__ import annotations

from mechopt.studies.catalogue import Study

__all__ = ["describe_simulator", "study_header"]


def describe_simulator(study: Study) -> str:
    """The simulator of a study: the user's command or callable, or the plug-in's own engine."""
    simulator = getattr(study.problem, "simulator", None)
    argv = getattr(simulator, "argv", None)
    if argv:
        timeout = getattr(simulator, "timeout_s", None)
        exchange = getattr(simulator, "exchange", "stdio")
        return (f"the command `{' '.join(argv)}` (exchange {exchange}"
                + (f", timeout {timeout:g} s" if timeout else "") + ")")
    target = getattr(simulator, "target", None)
    if target:
        return f"the Python callable {target}"
    engine = study.problem.settings().get("engine") if hasattr(study.problem, "settings") else None
    return f"mechopt's {engine} engine" if isinstance(engine, str) else f"mechopt's {study.kind} plug-in"


def study_header(study: Study) -> list[str]:
    """Two or three lines: the study and its description, the variables with bounds and units, the objective and
    the simulator."""
    problem = study.problem
    variables = ", ".join(f"{v.name} in [{v.lower:g}, {v.upper:g}]{(' ' + v.unit) if v.unit else ''}"
                          + (f" ({v.describe_kind()})" if v.discrete else "") for v in problem.variables)
    constraints = f"; constraints {', '.join(problem.constraints)}" if problem.constraints else ""
    objective = problem.output_label(problem.objective)
    title = f"study {study.name}" + (f": {study.description}" if study.description else "")
    return [title, f"  minimise {objective} over {variables}{constraints}",
            f"  simulator: {describe_simulator(study)}"]
