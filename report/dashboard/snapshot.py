"""One study as the live page shows it at one moment: progress, time left, best so far, failures, the front.

Pure computation on what :mod:`.store_reader` read; the figures (:mod:`.figures`) and the page draw it.
"""

from __future__ import annotations

import os
import socket
from collections import Counter
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

import numpy as np

from mechopt.report.dashboard.store_reader import StudyData

__all__ = ["StudySnapshot", "non_dominated", "run_state", "snapshot"]


@dataclass
class StudySnapshot:
    """Arrays and numbers of one study, in the order its samples were committed.

    Attributes
    ----------
    name, fingerprint : str
        The study.
    variables : list of dict
        name, unit, lower, upper of each design variable (``x1``... when no run described them).
    objectives : list of str
        Outputs minimised (several: a front); the first colours the designs.
    outputs : list of str
        Every numeric output, for the page's choice of colour.
    designs : (n, d) ndarray
        Every sampled design, in the variables' units.
    status : list of str
        ``ok``, ``infeasible`` or ``failed`` for each design.
    values : dict
        Output name -> (n,) array (NaN where the design has no such value).
    errors : list of str or None
        The one-line reason of each infeasible or failed design.
    summary : dict
        The numbers the page prints (state, done, planned, time left, best, failures, plan, messages, result).
    """

    name: str
    fingerprint: str
    variables: list[dict[str, Any]]
    objectives: list[str]
    outputs: list[str]
    designs: np.ndarray
    status: list[str]
    values: dict[str, np.ndarray]
    errors: list[str | None]
    summary: dict[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> np.ndarray:
        """(n,) bool: the designs whose simulation succeeded with a finite first objective."""
        return np.array([s == "ok" for s in self.status], dtype=bool) & np.isfinite(self.values[self.objectives[0]])


def non_dominated(F: np.ndarray) -> np.ndarray:
    """Which rows of F (n, m) no other row dominates (every objective minimised).

    Parameters
    ----------
    F : (n, m) ndarray
        Objective values, finite.

    Returns
    -------
    (n,) ndarray of bool
        True for the front; of equal rows, each is kept.
    """
    F = np.asarray(F, dtype=float)
    le = np.all(F[:, None, :] <= F[None, :, :], axis=2)
    lt = np.any(F[:, None, :] < F[None, :, :], axis=2)
    dominated = np.any(le & lt, axis=0)  # [i, j]: row i dominates row j
    return ~dominated


def run_state(run: Any, now: datetime) -> str:
    """``running``, ``finished``, or how it stopped: from the journal's end, else whether its process is alive."""
    if run is None:
        return "no run journal in the store (written by `mechopt study`)"
    if run.ended:
        return "finished" if run.outcome == "finished" else f"stopped: {run.outcome}"
    host, _, rest = run.owner.partition("/")
    pid = rest.partition("/")[0]
    if host == socket.gethostname() and pid.isdigit() and not _alive(int(pid)):
        return "stopped (its process is gone)"
    return "running"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _seconds(stamp: str) -> float:
    return datetime.fromisoformat(stamp).timestamp()


def _numeric_outputs(records: list) -> list[str]:
    """The outputs with numbers, those that vary from design to design first (a constant one is no objective)."""
    seen: dict[str, set] = {}
    for r in records:
        for k, v in r.outputs.items():
            if isinstance(v, int | float) and not isinstance(v, bool):
                seen.setdefault(k, set()).add(v)
    return sorted(seen, key=lambda k: len(seen[k]) < 2)


def _progress(data: StudyData, described: dict[str, Any], now: datetime, state: str) -> dict[str, Any]:
    """Simulations done and planned in the latest run, and the time left at its average pace so far."""
    n = len(data.records)
    run = data.latest
    held = int(described.get("held") or 0)
    planned = described.get("planned")
    done = n - held
    elapsed = now.timestamp() - _seconds(run.started) if run else None
    left = None
    if state == "running" and isinstance(planned, int) and elapsed is not None:
        remaining = max(0, planned - done)
        if done > 0:
            # The run's own pace, its method's computing between simulations included.
            left = remaining * elapsed / done
        elif described.get("expected_s"):
            left = max(0.0, float(described["expected_s"]) - elapsed)
    # How long ago the store last heard of the study: on another host, a killed run reads "running" but goes quiet.
    quiet = now.timestamp() - max(_seconds(r.timestamp) for r in data.records) if data.records else None
    return {"records": n, "held": held, "done": done, "planned": planned, "elapsed_s": elapsed, "left_s": left,
            "quiet_s": quiet}


def snapshot(data: StudyData, objective: str | None = None, now: datetime | None = None) -> StudySnapshot:
    """The study's snapshot.

    Parameters
    ----------
    data : StudyData
        What the store holds about the study.
    objective : str, optional
        Output that colours the designs (default: the run's first objective, else the first numeric output).
    now : datetime, optional
        The time of the snapshot (aware, UTC); default now.

    Returns
    -------
    StudySnapshot
    """
    now = now or datetime.now().astimezone()
    run = data.latest
    described = data.description
    records = data.records
    d = len(records[0].design) if records else len(described.get("variables", [])) or 1
    variables = described.get("variables") or [{"name": f"x{i + 1}", "unit": ""} for i in range(d)]
    outputs = _numeric_outputs(records)
    objectives = [o for o in described.get("objectives", []) if o] or outputs[:1] or ["objective"]
    if objective in outputs and objective not in objectives[:1]:
        objectives = [objective, *[o for o in objectives if o != objective]]
    values = {k: np.array([r.value(k) for r in records], dtype=float) for k in {*outputs, *objectives}}
    designs = np.array([r.design for r in records], dtype=float).reshape(len(records), d)
    snap = StudySnapshot(data.name, data.fingerprint, variables, objectives, outputs, designs,
                         [r.status for r in records], values, [r.error for r in records])
    state = run_state(run, now)
    summary = {"state": state, **_progress(data, described, now, state), "method": described.get("method", ""),
               "units": described.get("units", {}), "plan": described.get("plan", []),
               "messages": [f"{stamp[11:19]}  {text}" for stamp, text in data.messages],
               "runs": len(data.runs), "failures": _failures(snap), "best": _best(snap)}
    if data.result:
        summary["result"] = {"message": data.result.get("message"), "optimum": data.result.get("optimum", {})}
    snap.summary = summary
    return snap


def _failures(snap: StudySnapshot) -> dict[str, Any]:
    """How many designs failed or were infeasible, and the most common reasons with their counts."""
    bad = [(s, e or "") for s, e in zip(snap.status, snap.errors, strict=True) if s != "ok"]
    reasons = Counter(f"{s}: {e[:160]}" for s, e in bad)
    return {"failed": sum(s == "failed" for s, _ in bad), "infeasible": sum(s == "infeasible" for s, _ in bad),
            "reasons": reasons.most_common(8)}


def _best(snap: StudySnapshot) -> dict[str, Any] | None:
    """The best design so far on the first objective: its number, variables and outputs."""
    ok = snap.ok
    if not ok.any():
        return None
    f = np.where(ok, snap.values[snap.objectives[0]], np.inf)
    i = int(np.argmin(f))
    return {"index": i + 1, "design": {v["name"]: float(x) for v, x in zip(snap.variables, snap.designs[i],
                                                                           strict=False)},
            "outputs": {k: float(snap.values[k][i]) for k in snap.objectives}}
