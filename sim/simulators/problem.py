"""A design problem whose evaluator is a user's simulator, and everything else its mechanism plug-in's.

The plug-in keeps what is cheap and mechopt's own — the variables and bounds, the constraint margins, where the
lines may be sampled, the search screen, the drawings — and the simulator (an external command or a Python
function) replaces only :meth:`evaluate`.  Attributes the wrapper does not define are read from the plug-in's problem
(``mechanism``, ``reconstruction``...), except its fast batch evaluator: a brute-force ground truth of mechopt's own
engine says nothing about the user's simulator.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from mechopt.optimize.problem import DesignProblem, Variable

__all__ = ["ExternalProblem", "Simulator"]

# Evaluators of the plug-in's own engine: not the simulator's, so not offered by the wrapper.
_NOT_DELEGATED = frozenset({"evaluate_batch"})


class Simulator(Protocol):
    """What :class:`ExternalProblem` needs of a simulator (the command and the callable simulators)."""

    outputs: tuple[str, ...]

    def run(self, design: Mapping[str, float], units: Mapping[str, str] | None = None) -> dict[str, Any]: ...

    def settings(self) -> dict[str, Any]: ...


class ExternalProblem(DesignProblem):
    """The plug-in's problem with its evaluator replaced by a user's simulator.

    Parameters
    ----------
    base : DesignProblem
        The mechanism plug-in's problem (variables, constraints, margins, figures).
    simulator : Simulator
        Evaluates one design: ``run({name: value}, {name: unit}) -> {output: value}``.
    objective : str
        The output minimised (one of ``simulator.outputs``).
    fit : str
        ``"square"`` or ``"value"`` (see :class:`~mechopt.optimize.problem.DesignProblem`).
    """

    def __init__(self, base: DesignProblem, simulator: Simulator, objective: str, fit: str) -> None:
        self.base = base
        self.simulator = simulator
        self.outputs = tuple(simulator.outputs)
        self.objective = objective
        self.fit = fit

    def __getattr__(self, name: str) -> Any:
        # Only called for attributes not found normally; "base" guards unpickling, which runs before __dict__ is set.
        if name == "base" or name.startswith("__") or name in _NOT_DELEGATED:
            raise AttributeError(name)
        return getattr(self.base, name)

    @property
    def name(self) -> str:  # type: ignore[override]
        return self.base.name

    @property
    def variables(self) -> tuple[Variable, ...]:  # type: ignore[override]
        return tuple(self.base.variables)

    @property
    def constraints(self) -> tuple[str, ...]:  # type: ignore[override]
        return tuple(self.base.constraints)

    @property
    def surrogate_order(self) -> tuple[int, ...] | None:  # type: ignore[override]
        return self.base.surrogate_order

    @property
    def fd_step(self) -> float:  # type: ignore[override]
        # A user's simulator (a CAD batch run, a solver with tolerances) is assumed noisy until it says otherwise.
        return 1e-3

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        """Outputs of design ``x`` (the variables' units) from the simulator.

        Raises
        ------
        InfeasibleDesignError
            The simulator said the design cannot be simulated.
        SimulatorFailure
            The simulator failed (recorded by the sampler as a failed design).
        """
        return self.simulator.run(self.design_dict(x), {v.name: v.unit for v in self.variables})

    def margins(self, X: np.ndarray) -> np.ndarray:
        """The plug-in's constraint margins."""
        return self.base.margins(X)

    def sampleable(self, X: np.ndarray) -> np.ndarray:
        """The plug-in's region where lines may be simulated."""
        return self.base.sampleable(X)

    def screen(self, X: np.ndarray) -> np.ndarray:
        """The plug-in's cheap feasibility screen."""
        return self.base.screen(X)

    def describe(self, x: np.ndarray) -> str:
        """The plug-in's one-line description of a design."""
        return self.base.describe(x)

    def figures(self, designs: Mapping[str, np.ndarray], out: Path) -> dict[str, Path]:
        """The plug-in's figures (drawn with mechopt's own engine, not the simulator)."""
        return self.base.figures(designs, out)

    def settings(self) -> dict[str, Any]:
        """The simulator's settings, and the plug-in's problem and settings (its region and rules)."""
        base = self.base
        return {"simulator": self.simulator.settings(),
                "base": {"problem": f"{type(base).__module__}.{type(base).__qualname__}",
                         "version": base.version, "settings": base.settings()}}
