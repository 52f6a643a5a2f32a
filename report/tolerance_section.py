"""The report's section on tolerances: how far the optimum lies from each active margin (warnings when a tolerance
makes one fail) and, when the study asks for it, the robust optimum beside the nominal one."""

from __future__ import annotations

from typing import Any

import numpy as np

from mechopt.optimize.analysis.margin_distance import margin_distances

__all__ = ["tolerance_lines", "tolerance_summary"]


def tolerance_summary(problem, result: Any, study: Any) -> dict[str, Any]:
    """``result.json``'s ``tolerances``: the margins of the nominal optimum, and the robust optimum if any."""
    declared = getattr(study, "tolerances", None)
    nominal = np.asarray(result.get("nominal_x", result.x), dtype=float)
    distances = margin_distances(problem, nominal, declared.tolerances if declared else None)
    robust = result.get("robust")
    return {"margins": distances, "declared": declared is not None,
            "robust": None if robust is None else {**robust.to_dict(problem), "lines": robust.lines(problem)}}


def tolerance_lines(r: dict[str, Any]) -> list[str]:
    """Markdown of a :func:`tolerance_summary` (empty when there is nothing to say)."""
    t = r.get("tolerances")
    if not t or (not t["margins"]["lines"] and t["robust"] is None):
        return []
    margins = t["margins"]["lines"]
    if t["robust"] is not None:  # the distances are those of the nominal optimum, which the robust one moved from
        margins = [line.replace("of the optimum", "of the nominal optimum") for line in margins]
    lines = ["", "## Margins and tolerances", "", *margins]
    if not t["declared"]:
        lines += ["", "(The study declares no `[tolerances]`: a drawing's default is assumed.)"]
    if t["robust"] is not None:
        rb = t["robust"]
        lines += ["", f"**Robust optimum** (each margin violated on at most {100 * rb['max_violation']:g} % of the "
                  "parts; the optimum above is the robust one):", "",
                  "| design | objective (simulated) | P(a margin violated) | scatter mean |", "|---|---|---|---|"]
        for name, x, fun, s in (("robust", rb["x"], rb["fun"], rb["robust"]),
                                ("nominal", rb["nominal_x"], rb["nominal_fun"], rb["nominal"])):
            design = ", ".join(f"{k} {v:.4f}" for k, v in x.items())
            lines.append(f"| {name}: {design} | {fun:.6g} | {s['violation']['any']:.4f} | {s['mean']:.6g} |")
        lines += ["", f"The price of robustness: {100 * rb['price']:+.2f} % on the objective, "
                  f"{rb['simulations']} simulations beyond the nominal run ({rb['message']})."]
    return lines
