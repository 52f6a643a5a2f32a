"""What a report says of a problem's discrete variables: each variable's kind, how many designs the space holds,
and what holding the answer to the allowed designs cost against reference designs off the grid (a continuous
optimum)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["allowed_designs_lines", "allowed_designs_summary", "variable_summary"]


def variable_summary(v: Any) -> dict[str, Any]:
    """A variable as result.json lists it: name, unit, bounds, kind, and the step, count or catalogue."""
    row: dict[str, Any] = {"name": v.name, "unit": v.unit, "lower": v.lower, "upper": v.upper, "kind": v.kind}
    if v.discrete:
        row["count"] = v.count
    if v.step is not None:
        row["step"] = v.step
    if v.values is not None:
        row["values"] = list(v.values)
    return row


def allowed_designs_summary(problem: Any, budget: int, references: Mapping[str, Mapping[str, Any]],
                            fun: float) -> dict[str, Any] | None:
    """The discrete variables, the number of designs when finite, whether the budget covers them, and the cost of
    the answer against each feasible reference design off the grid (% of its objective); None without discrete
    variables.

    Parameters
    ----------
    problem : DesignProblem
    budget : int
        The method's simulations.
    references : mapping
        The run's reference designs by name (``design``, ``status``, ``outputs``, ``feasible``).
    fun : float
        The answer's objective, as minimised.
    """
    if not problem.discrete.any():
        return None
    count = problem.design_count
    costs = {}
    for name, ref in references.items():
        x = np.array([ref["design"][n] for n in problem.names])
        if name == "optimum" or ref["status"] != "ok" or not ref["feasible"] or problem.on_grid(x)[0]:
            continue
        value = problem.objective_value(ref["outputs"])
        if value:
            costs[name] = {"objective": value, "cost_pct": 100.0 * (fun / value - 1.0)}
    return {"discrete": [v.name for v in problem.variables if v.discrete], "design_count": count,
            "budget_covers": count is not None and budget >= count, "cost_against": costs}


def allowed_designs_lines(r: Mapping[str, Any]) -> list[str]:
    """The report's section on the allowed designs (empty without discrete variables)."""
    a = r.get("allowed_designs")
    if not a:
        return []
    kinds = ", ".join(f"{v['name']} {_kind_text(v)}" for v in r["problem"]["variables"])
    count = a["design_count"]
    space = (f"The space holds {count:,} distinct designs" + (", all within the budget" if a["budget_covers"] else "")
             if count is not None else "The space is infinite (a continuous variable)")
    lines = ["", "## Allowed designs", "", f"Variables: {kinds}. {space}; every design simulated and the answer lie "
             "on the variables' grids, integers and catalogues."]
    obj = r["problem"]["objective"]
    for name, c in a["cost_against"].items():
        lines.append(f"Against the design `{name}` (off the grid, {obj} {c['objective']:.6g}), holding the answer to "
                     f"the allowed designs costs {c['cost_pct']:+.3f} % of {obj}.")
    return lines


def _kind_text(v: Mapping[str, Any]) -> str:
    if v.get("kind") == "grid":
        return f"(step {v['step']:g}{(' ' + v['unit']) if v['unit'] else ''}, {v['count']} values)"
    if v.get("kind") == "integer":
        return f"(integer, {v['count']} values)"
    if v.get("kind") == "catalogue":
        return f"(catalogue {v['values']})"
    return "(continuous)"
