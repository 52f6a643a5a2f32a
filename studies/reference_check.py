"""Whether a study's answer is worse than one of its own reference designs, said in one line.

A study's reference designs (the original design, the paper's optimum, the best design found earlier) are simulated
with every run.  When one of them is feasible and better than the run's answer, the run missed a design the user
already knows; the final line and the report say so, with both values, instead of presenting the answer as the
optimum.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = ["better_references", "reference_warning"]

# Simulations repeat to the last digit; below this relative difference a reference ties with the answer.
_RELATIVE_TIE = 1e-9


def better_references(references: Mapping[str, Mapping[str, Any]], objective: str,
                      fun: float) -> list[tuple[str, float]]:
    """The reference designs that are simulated, feasible and better than the answer, best first.

    Parameters
    ----------
    references : mapping
        Name -> ``{"status", "outputs", "feasible", "allowed"}`` of each reference design (the entry ``"optimum"``, the
        answer itself, is skipped).
    objective : str
        Name of the output minimised.
    fun : float
        The answer's objective, in the objective's unit.

    Returns
    -------
    list of (str, float)
        Name and objective of each better reference design.
    """
    better = []
    for name, ref in references.items():
        # A reference off the variables' grids (a continuous optimum) is no design the run could have returned.
        if name == "optimum" or ref.get("status") != "ok" or not ref.get("feasible", True) \
                or not ref.get("allowed", True):
            continue
        value = ref.get("outputs", {}).get(objective)
        if value is None or not math.isfinite(value):
            continue
        if not math.isfinite(fun) or value < fun - _RELATIVE_TIE * max(1.0, abs(fun)):
            better.append((name, float(value)))
    return sorted(better, key=lambda item: item[1])


def reference_warning(references: Mapping[str, Mapping[str, Any]], objective: str, fun: float,
                      unit: str = "") -> str | None:
    """One line when the answer is worse than a reference design of the study (the best of them), else None."""
    better = better_references(references, objective, fun)
    if not better:
        return None
    name, value = better[0]
    u = f" {unit}" if unit else ""
    ratio = f", {fun / value:.3g} times lower" if value > 0 and math.isfinite(fun) and fun > 0 else ""
    n = len(better) - 1
    others = f" (and {n} other reference design{'s' if n > 1 else ''})" if n else ""
    return (f"warning: this answer ({objective} {fun:.6g}{u}) is worse than the study's own reference design "
            f"{name!r} ({objective} {value:.6g}{u}{ratio}){others}: the run missed a better design; try a larger "
            "budget, another method, or start from it with --x0")
