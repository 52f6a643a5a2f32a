"""The ``[simulator]`` section of a study file: which simulator replaces the plug-in's evaluator, and how it runs.

::

    [simulator]
    command = ["{python}", "my_sim.py"]   # an argv list, never a shell string; or callable = "my_sim:simulate"
    outputs = ["t_rms", "t_max"]          # what it returns (finite numbers)
    objective = "t_rms"                   # default: the plug-in's objective (kind "external": the first output)
    fit = "square"                        # default: the plug-in's fit for its objective, else "value"
    timeout_s = 60                        # command only (default 3600)
    exchange = "stdio"                    # command only: or "files" (design.json in, outputs.json out)
    workdir = "runs"                      # command only: per-design work folders, relative to the study file
    keep = "failed"                       # command only: or "all" (keep every design's work folder)
    env = { MY_LICENSE = "..." }          # command only: added to the environment
    seconds_per_run = 85                  # what one simulation costs (s): the plan before a run estimates from it

``{python}`` in the command is the interpreter running mechopt; ``{study}`` the study file's folder.
"""

from __future__ import annotations

import sys

from mechopt.errors import StudyError
from mechopt.optimize.problem import FITS, DesignProblem
from mechopt.sim.simulators.command import EXCHANGES, KEEP, CommandSimulator
from mechopt.sim.simulators.outputs import INFEASIBLE_KEY
from mechopt.sim.simulators.problem import ExternalProblem
from mechopt.sim.simulators.python_callable import CallableSimulator, module_file, split_target
from mechopt.studies.study_file import StudyFile

__all__ = ["SIMULATOR_KEYS", "declared_seconds_per_run", "simulator_from_study", "with_simulator"]

# seconds_per_run is not part of the simulator (nor of the samples' fingerprint): only the plan reads it.
_COMMON_KEYS = {"outputs", "objective", "fit", "seconds_per_run"}
_COMMAND_KEYS = {"command", "timeout_s", "exchange", "workdir", "keep", "env"}
SIMULATOR_KEYS = _COMMON_KEYS | _COMMAND_KEYS | {"callable"}


def _outputs(study: StudyFile, section: dict) -> tuple[str, ...]:
    value = section.get("outputs")
    ok = isinstance(value, list) and value and all(isinstance(v, str) and v.isidentifier() for v in value)
    if not ok:
        raise StudyError(f"{study.where}: key simulator.outputs = {value!r} must be a non-empty list of output names "
                         "such as [\"t_rms\", \"t_max\"]")
    if len(set(value)) != len(value) or INFEASIBLE_KEY in value:
        raise StudyError(f"{study.where}: key simulator.outputs = {value!r} must be distinct names other than "
                         f"{INFEASIBLE_KEY!r}")
    return tuple(value)


def declared_seconds_per_run(study: StudyFile) -> float | None:
    """``[simulator] seconds_per_run``: the declared wall time of one simulation (s), None when not declared.

    Raises
    ------
    StudyError
        A value that is not a positive finite number.
    """
    section = study.table("simulator", required=False)
    if "seconds_per_run" not in section:
        return None
    return study.number(section, "seconds_per_run", "simulator", positive=True)


def simulator_from_study(study: StudyFile) -> CommandSimulator | CallableSimulator:
    """The simulator of a study file's ``[simulator]`` section.

    Raises
    ------
    StudyError
        A missing, unknown or ill-typed key, or a callable whose module cannot be found.
    """
    section = study.table("simulator", SIMULATOR_KEYS)
    folder = str(study.path.parent.resolve())
    outputs = _outputs(study, section)
    if ("command" in section) == ("callable" in section):
        raise StudyError(f"{study.where}: section [simulator] needs exactly one of command (an argv list) or "
                         "callable (\"package.module:function\")")
    if "callable" in section:
        extra = sorted(_COMMAND_KEYS & set(section))
        if extra:
            raise StudyError(f"{study.where}: key simulator.{extra[0]} applies to a command, not to a callable")
        target = study.string(section, "callable", "simulator")
        module, _ = split_target(target)
        if module_file(module, folder) is None and module not in sys.builtin_module_names:
            raise StudyError(f"{study.where}: key simulator.callable = {target!r}: module {module!r} not found beside "
                             f"the study file ({folder}) nor on sys.path")
        return CallableSimulator(target, outputs, folder)
    argv = section["command"]
    if isinstance(argv, str):
        raise StudyError(f"{study.where}: key simulator.command = {argv!r} must be an argv list such as "
                         "[\"python\", \"my_sim.py\"], never a shell string")
    if not isinstance(argv, list) or not argv or not all(isinstance(a, str) and a for a in argv):
        raise StudyError(f"{study.where}: key simulator.command = {argv!r} must be a non-empty list of strings")
    env = study.table("simulator.env", required=False)
    bad = next((k for k, v in env.items() if not isinstance(v, str)), None)
    if bad is not None:
        raise StudyError(f"{study.where}: key simulator.env.{bad} = {env[bad]!r} must be a string")
    workdir = section.get("workdir")
    if workdir is not None:
        workdir = str((study.path.parent / study.string(section, "workdir", "simulator")).resolve())
    return CommandSimulator(
        argv=tuple(argv), outputs=outputs, folder=folder,
        timeout_s=study.number(section, "timeout_s", "simulator", 3600.0, positive=True),
        exchange=study.string(section, "exchange", "simulator", "stdio", EXCHANGES),
        workdir=workdir, env=tuple(sorted(env.items())),
        keep=study.string(section, "keep", "simulator", "failed", KEEP),
    )


def with_simulator(study: StudyFile, base: DesignProblem) -> ExternalProblem:
    """The plug-in's problem with its evaluator replaced by the study's ``[simulator]``.

    Parameters
    ----------
    study : StudyFile
        The study file (it has a ``[simulator]`` section).
    base : DesignProblem
        What the mechanism plug-in returned.

    Raises
    ------
    StudyError
        A bad ``[simulator]`` section, or an objective that is not among its outputs.
    """
    section = study.table("simulator", SIMULATOR_KEYS)
    simulator = simulator_from_study(study)
    declared_seconds_per_run(study)  # checked when the study is loaded, before any plan or simulation
    outputs = simulator.outputs
    if "objective" in section:
        objective = study.string(section, "objective", "simulator", choices=outputs)
    elif base.objective in outputs:
        objective = base.objective
    elif not base.objective:
        objective = outputs[0]
    else:
        raise StudyError(f"{study.where}: the plug-in's objective {base.objective!r} is not among simulator.outputs "
                         f"{list(outputs)}; add it or name simulator.objective")
    default_fit = base.fit if objective == base.objective else "value"
    fit = study.string(section, "fit", "simulator", default_fit, FITS)
    return ExternalProblem(base, simulator, objective, fit)
