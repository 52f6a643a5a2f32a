"""The journal of the runs that fill a sample store: what each run is (its study, variables, objectives, plan) and the
messages it printed, so that a page reading the store alone can show a run while it goes on.

Two tables beside ``samples``, created by the first run that writes a journal (a store without them is still a
store of the current schema): ``runs`` (one row per run: the fingerprint of its problem, its name, a JSON
description, the owner ``HOST/PID/UUID``, start and end times, and how it ended) and ``run_messages`` (the run's
lines, in order).  A page reads them with :func:`read_runs` and :func:`read_messages`; nothing reads the running
process.
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mechopt.runs.claims import new_owner
from mechopt.runs.sample_record import utc_timestamp
from mechopt.runs.store_connection import StoreConnection

__all__ = ["JournalRun", "RunJournal", "describe_run", "read_messages", "read_runs"]

_TABLES = (
    """
    CREATE TABLE IF NOT EXISTS runs (
        id          INTEGER PRIMARY KEY,
        fingerprint TEXT NOT NULL,
        name        TEXT NOT NULL,
        description TEXT NOT NULL DEFAULT '{}',
        owner       TEXT NOT NULL,
        started     TEXT NOT NULL,
        ended       TEXT,
        outcome     TEXT
    )""",
    """
    CREATE TABLE IF NOT EXISTS run_messages (
        id        INTEGER PRIMARY KEY,
        run       INTEGER NOT NULL,
        timestamp TEXT NOT NULL,
        text      TEXT NOT NULL
    )""",
)


@dataclass(frozen=True)
class JournalRun:
    """One run as the journal holds it.

    Attributes
    ----------
    id : int
        Row id (runs started later have larger ids).
    fingerprint : str
        Fingerprint of the run's problem: its rows in ``samples``.
    name : str
        The study's name.
    description : dict
        :func:`describe_run`'s JSON: variables, objectives, outputs, method, plan lines and counts.
    owner : str
        ``HOST/PID/UUID`` of the process that ran it.
    started, ended : str or None
        ISO 8601 UTC times; ``ended`` is None while the run goes on (or if it was killed).
    outcome : str or None
        ``"finished"``, or the line the run stopped with.
    """

    id: int
    fingerprint: str
    name: str
    description: dict[str, Any]
    owner: str
    started: str
    ended: str | None
    outcome: str | None


def describe_run(problem: Any, plan: Any = None, method: str = "", opening: Sequence[str] = (),
                 out: Path | None = None, held: int = 0) -> dict[str, Any]:
    """The JSON description of a run that a page needs to show it.

    Parameters
    ----------
    problem : DesignProblem
        The run's problem: its variables (name, unit, bounds), objective (or ``objectives`` when it has several),
        outputs and their units.
    plan : RunPlan, optional
        The plan printed before the run: ``budget``, ``new`` (most simulations to run), ``total``, ``seconds``
        (expected simulation time, s, or None).
    method : str
        The optimizer's name.
    opening : sequence of str
        The lines printed before the first simulation (the study, its variables, the plan).
    out : Path, optional
        The run's output folder.
    held : int
        Records of the problem's fingerprint the store held when the run started.

    Returns
    -------
    dict
    """
    objectives = list(getattr(problem, "objectives", None) or [problem.objective])
    return {
        "variables": [{"name": v.name, "unit": v.unit, "lower": v.lower, "upper": v.upper}
                      for v in problem.variables],
        "objectives": [str(o) for o in objectives],
        "outputs": list(problem.outputs),
        "units": {str(k): str(v) for k, v in dict(getattr(problem, "output_units", {}) or {}).items()},
        "method": method,
        "plan": list(opening),
        "budget": getattr(plan, "budget", None),
        "planned": getattr(plan, "new", None),
        "expected_s": getattr(plan, "seconds", None),
        "held": int(held),
        "out": str(Path(out).resolve()) if out is not None else None,
    }


class RunJournal:
    """The writer of one run's journal rows, on its own connection to the store.

    Parameters
    ----------
    path : Path
        The sample store.
    fingerprint : str
        Fingerprint of the run's problem.
    name : str
        The study's name.
    description : dict
        :func:`describe_run`'s JSON.
    timeout : float
        Seconds to wait for the store's lock.
    """

    def __init__(self, path: Path, fingerprint: str, name: str, description: dict[str, Any],
                 timeout: float = 30.0) -> None:
        self._db = StoreConnection(Path(path), timeout)
        # A run on a read-only store (every design already in it) still runs; it only leaves no journal.
        self._open = self._db.read_only is None
        self.run_id: int | None = None
        if not self._open:
            self._db.close()
            return
        with self._db.write("starting the run's journal") as conn:
            for statement in _TABLES:
                conn.execute(statement)
            self.run_id = conn.execute(
                "INSERT INTO runs (fingerprint, name, description, owner, started) VALUES (?, ?, ?, ?, ?)",
                (fingerprint, name, json.dumps(description), new_owner(), utc_timestamp()),
            ).lastrowid

    def message(self, text: str) -> None:
        """Record one line the run printed."""
        if not self._open:
            return
        with self._db.write("recording a message of the run") as conn:
            conn.execute("INSERT INTO run_messages (run, timestamp, text) VALUES (?, ?, ?)",
                         (self.run_id, utc_timestamp(), str(text)))

    def tee(self, log: Callable[[str], None]) -> Callable[[str], None]:
        """A log function that prints with ``log`` and records the line."""
        def both(line: str) -> None:
            log(line)
            self.message(line)

        return both

    def finish(self, outcome: str = "finished") -> None:
        """Record the end of the run and close the connection (idempotent)."""
        if not self._open:
            return
        with self._db.write("closing the run's journal") as conn:
            conn.execute("UPDATE runs SET ended = ?, outcome = ? WHERE id = ?", (utc_timestamp(), outcome, self.run_id))
        self._db.close()
        self._open = False


def _has_journal(conn: sqlite3.Connection) -> bool:
    names = {row[0] for row in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    return {"runs", "run_messages"} <= names


def read_runs(conn: sqlite3.Connection) -> list[JournalRun]:
    """Every run of the journal, oldest first (none for a store that has no journal).

    Parameters
    ----------
    conn : sqlite3.Connection
        A connection to the store (read-only is enough).

    Returns
    -------
    list of JournalRun
    """
    if not _has_journal(conn):
        return []
    rows = conn.execute(
        "SELECT id, fingerprint, name, description, owner, started, ended, outcome FROM runs ORDER BY id"
    ).fetchall()
    runs = []
    for rid, fp, name, description, owner, started, ended, outcome in rows:
        try:
            described = json.loads(description)
        except ValueError:
            described = {}
        runs.append(JournalRun(rid, fp, name, described if isinstance(described, dict) else {}, owner, started,
                               ended, outcome))
    return runs


def read_messages(conn: sqlite3.Connection, run_id: int, limit: int = 500) -> list[tuple[str, str]]:
    """The last ``limit`` lines of a run, oldest first, as (timestamp, text).

    Parameters
    ----------
    conn : sqlite3.Connection
        A connection to the store.
    run_id : int
        :attr:`JournalRun.id`.
    limit : int
        Most lines returned.

    Returns
    -------
    list of (str, str)
    """
    if not _has_journal(conn):
        return []
    rows = conn.execute("SELECT timestamp, text FROM run_messages WHERE run = ? ORDER BY id DESC LIMIT ?",
                        (run_id, limit)).fetchall()
    return rows[::-1]
