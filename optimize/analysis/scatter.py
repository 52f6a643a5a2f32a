"""Manufacturing tolerances of the design variables, and the designs a tolerance scatters a nominal design into.

A tolerance ``t`` of a variable is the ± deviation a part is made to, in the variable's unit.  Two readings:
``"uniform"`` (every deviation in [-t, t] equally likely: a worst-case drawing tolerance) and ``"normal"`` (the
deviation is normal with standard deviation t / 3: a process whose ±3σ spread is the tolerance).  The variables
scatter independently.  The scattered designs are a scrambled Sobol set mapped through the distribution's inverse
CDF: the same seed gives the same designs for every nominal design (common random numbers), so a robust optimiser
compares designs on the same scatter.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.problem import DesignProblem, as_design_array

__all__ = ["DISTRIBUTIONS", "STATISTICS", "Tolerances", "as_tolerances", "check_design_in_box",
           "check_max_violation"]

#: How a tolerance is read: ``uniform`` on [-t, t], or ``normal`` with σ = t / 3.
DISTRIBUTIONS = ("uniform", "normal")
#: What a robust optimum minimises over the scatter: the mean, or a quantile given as a number in (0, 1).
STATISTICS = ("mean",)


@dataclass(frozen=True)
class Tolerances:
    """Tolerances of a problem's variables.

    Parameters
    ----------
    values : mapping of str to float
        ± tolerance per variable name, in the variable's unit; a variable not named is made exactly.
    distribution : str
        ``"uniform"`` (deviations uniform on [-t, t]) or ``"normal"`` (σ = t / 3).
    statistic : str or float
        What a robust optimum minimises over the scatter: ``"mean"`` or a quantile level in (0, 1) (0.95: the
        objective 95 % of the parts stay below).
    samples : int
        Scattered designs per Monte Carlo estimate (a power of two: a scrambled Sobol set).
    seed : int
        Seed of the scrambling.
    robust_simulations : int
        Most simulations a robust optimum (:func:`mechopt.minimize` with ``tolerances=``) adds to the nominal run.
    """

    values: Mapping[str, float] = field(default_factory=dict)
    distribution: str = "uniform"
    statistic: str | float = "mean"
    samples: int = 4096
    seed: int = 0
    robust_simulations: int = 40

    def __post_init__(self) -> None:
        if not isinstance(self.values, Mapping):
            raise InputError(f"tolerances = {self.values!r}: expected a mapping of variable names to ± values")
        for name, value in self.values.items():
            if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value < 0:
                raise InputError(f"tolerance of {name} = {value!r}: expected a finite number >= 0 (± in its unit)")
        object.__setattr__(self, "values", {str(k): float(v) for k, v in self.values.items()})
        if self.distribution not in DISTRIBUTIONS:
            raise InputError(f"distribution = {self.distribution!r}: expected one of {', '.join(DISTRIBUTIONS)}")
        s = self.statistic
        if not (s in STATISTICS or (isinstance(s, float) and not isinstance(s, bool) and 0.0 < s < 1.0)):
            raise InputError(f"statistic = {s!r}: expected 'mean' or a quantile level in (0, 1) such as 0.95")
        n = self.samples
        if isinstance(n, bool) or not isinstance(n, int) or n < 64 or n & (n - 1):
            raise InputError(f"samples = {n!r}: expected a power of two >= 64 (a scrambled Sobol set)")
        r = self.robust_simulations
        if isinstance(r, bool) or not isinstance(r, int) or r < 0:
            raise InputError(f"robust_simulations = {r!r}: expected a whole number >= 0")

    def vector(self, problem: DesignProblem) -> np.ndarray:
        """The tolerances (d,) in the problem's variable order, checked against its variables.

        Raises
        ------
        InputError
            A name that is not a variable, or a tolerance larger than the variable's range.
        """
        unknown = sorted(set(self.values) - set(problem.names))
        if unknown:
            raise InputError(f"tolerance for unknown variable {unknown[0]!r}; expected one of {list(problem.names)}")
        t = np.array([self.values.get(v.name, 0.0) for v in problem.variables])
        for v, ti in zip(problem.variables, t, strict=True):
            if ti > v.upper - v.lower:
                raise InputError(f"tolerance of {v.name} = {ti:g} {v.unit}: expected at most its range "
                                 f"{v.upper - v.lower:g} {v.unit}")
        if not np.any(t > 0):
            raise InputError(f"every tolerance is zero: expected a tolerance > 0 for some of {list(problem.names)}")
        return t

    def deviations(self, problem: DesignProblem, n: int | None = None, seed: int | None = None) -> np.ndarray:
        """Deviations (n, d) from a nominal design, in the variables' units (common to every nominal design)."""
        from scipy.stats import norm, qmc

        t = self.vector(problem)
        n = self.samples if n is None else n
        u = qmc.Sobol(problem.dim, seed=self.seed if seed is None else seed).random(n)
        if self.distribution == "uniform":
            return (2.0 * u - 1.0) * t
        return norm.ppf(np.clip(u, 1e-12, 1.0 - 1e-12)) * (t / 3.0)

    def describe(self, problem: DesignProblem) -> str:
        """One line: ``±0.1 mm on oa, ab, bc (uniform)``."""
        t = self.vector(problem)
        parts = [f"{v.name} ±{ti:g}{(' ' + v.unit) if v.unit else ''}"
                 for v, ti in zip(problem.variables, t, strict=True) if ti > 0]
        how = "uniform" if self.distribution == "uniform" else "normal, tolerance = 3σ"
        return f"{', '.join(parts)} ({how})"


def as_tolerances(value: Any, problem: DesignProblem | None = None) -> Tolerances:
    """A :class:`Tolerances` from itself, a mapping of name -> ± value, or one number for every variable."""
    if isinstance(value, Tolerances):
        out = value
    elif isinstance(value, Mapping):
        out = Tolerances(dict(value))
    elif isinstance(value, int | float) and not isinstance(value, bool) and problem is not None:
        out = Tolerances(dict.fromkeys(problem.names, float(value)))
    else:
        raise InputError(f"tolerances = {value!r:.80}: expected a mapping such as {{'oa': 0.1}}, a number or "
                         "a mechopt.Tolerances")
    if problem is not None:
        out.vector(problem)
    return out


def check_max_violation(value: Any) -> float:
    """A target probability of violation in (0, 0.5), or a one-line InputError."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0.0 < value < 0.5:
        raise InputError(f"max_violation = {value!r}: expected a probability in (0, 0.5), such as 0.01")
    return float(value)


def check_design_in_box(problem: DesignProblem, x: Any, what: str = "design") -> np.ndarray:
    """One design (d,) checked finite and inside the variables' bounds."""
    x = as_design_array(x, problem.dim, what)
    if x.shape[0] != 1:
        raise InputError(f"{what}: expected one design of {problem.dim} values, got {x.shape[0]}")
    for v, xi in zip(problem.variables, x[0], strict=True):
        if not v.lower <= xi <= v.upper:
            raise InputError(f"{what}: {v.name} = {xi:g} {v.unit} is outside its bounds [{v.lower:g}, {v.upper:g}]")
    return x[0]
