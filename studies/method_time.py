"""The methods' own computing time, measured per method, dimension and budget, for the plan of a study.

A plan that counts simulations only promised a re-run with every simulation in the store in "0 s", and a run of
cheap simulations in seconds, when the method's model fits and searches take minutes.  The table
``method_time.json`` beside this module is measured by ``benchmarks/bench_method_time.py`` (its command, date and
machine are in the file); :func:`method_seconds` reads it for the plan.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

__all__ = ["TABLE_FILE", "method_seconds", "method_time_line", "table_source"]

#: The measured table (written by ``benchmarks/bench_method_time.py``).
TABLE_FILE = Path(__file__).with_name("method_time.json")


@functools.cache
def _table() -> dict:
    try:
        return json.loads(TABLE_FILE.read_text())
    except (OSError, ValueError):
        return {"rows": []}


def table_source() -> str:
    """Where the figures come from, for the plan's line (e.g. ``"measured 2026-11-27 on 2 cores"``)."""
    table = _table()
    return f"measured {table.get('date', '?')} on {table.get('cores', '?')} cores" if table["rows"] else "not measured"


def method_seconds(method: str, dim: int, budget: int) -> float | None:
    """The method's own computing time for a run (s), from the measured table; None where it was not measured.

    Parameters
    ----------
    method : str
        A method's name.
    dim : int
        Design variables: the nearest measured dimension is used (the larger one on a tie).
    budget : int
        Simulations: interpolated linearly between the measured budgets, and in proportion to the budget outside
        them.

    Returns
    -------
    float or None
        Seconds on the machine of the table (see :func:`table_source`).
    """
    rows = [r for r in _table()["rows"] if r["method"] == method]
    if not rows:
        return None
    nearest = min({r["dim"] for r in rows}, key=lambda d: (abs(d - dim), -d))
    points = sorted((r["budget"], r["seconds"]) for r in rows if r["dim"] == nearest)
    if budget <= points[0][0]:
        return points[0][1] * budget / points[0][0]
    if budget >= points[-1][0]:
        return points[-1][1] * budget / points[-1][0]
    for (b0, s0), (b1, s1) in zip(points, points[1:], strict=False):
        if b0 <= budget <= b1:
            return s0 + (s1 - s0) * (budget - b0) / (b1 - b0)
    return None


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.0f} min" if seconds < 7200 else \
        f"{seconds / 3600:.1f} h"


def method_time_line(method_s: float | None, simulation_s: float | None) -> str:
    """The plan's line on the method's own computing, and the run's expected wall time with it."""
    if method_s is None:
        return "  the method's own computing: not measured for this method (benchmarks/bench_method_time.py)"
    total = "" if simulation_s is None else f"; expected wall time about {_duration(method_s + simulation_s)} in all"
    return (f"  the method's own computing: about {_duration(method_s)} ({table_source()}, "
            f"benchmarks/bench_method_time.py; a re-run whose simulations are all stored replays its answer){total}")
