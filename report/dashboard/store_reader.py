"""What the live page reads: a sample store (or a study's output folder and its store), opened read-only.

The page never talks to a running optimizer: it reads the rows a run commits to the store, the run's journal
(:mod:`mechopt.runs.run_journal`) and, once a run has ended, the ``result.json`` of its output folder.
"""

from __future__ import annotations

import json
import sqlite3
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import quote

from mechopt.errors import InputError
from mechopt.runs.run_journal import JournalRun, read_messages, read_runs
from mechopt.runs.sample_record import SampleRecord
from mechopt.runs.sample_rows import select_rows, status_filter

__all__ = ["StudyData", "find_store", "list_studies", "open_read_only", "read_study", "store_version"]

#: The store's name in a study's output folder.
STORE_NAME = "samples.sqlite"


def find_store(path: str | Path) -> Path:
    """The sample store named by ``path``: the file itself, or the store of a study's output folder.

    Parameters
    ----------
    path : str or Path
        An SQLite store, or an output folder holding ``samples.sqlite`` (or a ``result.json`` naming the store).

    Returns
    -------
    Path

    Raises
    ------
    InputError
        One line when nothing there is a store.
    """
    path = Path(path)
    if path.is_file():
        return path
    if not path.is_dir():
        raise InputError(f"{path}: no such file or folder; expected a sample store or a study's output folder")
    if (path / STORE_NAME).is_file():
        return path / STORE_NAME
    named = _result(path).get("store")
    if isinstance(named, str) and Path(named).is_file():
        return Path(named)
    raise InputError(f"{path}: the folder holds no {STORE_NAME} (nor a result.json naming a store); "
                     "give the path of the sample store")


def open_read_only(store: Path) -> sqlite3.Connection:
    """A read-only connection to a store; one line if the file is not a mechopt store.

    Raises
    ------
    InputError
        The file is not an SQLite database or holds no ``samples`` table.
    """
    try:
        conn = sqlite3.connect(f"file:{quote(str(Path(store).resolve()))}?mode=ro", uri=True, timeout=10.0)
        tables = {row[0] for row in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    except sqlite3.DatabaseError as exc:
        raise InputError(f"{store} is not a mechopt sample store ({exc})") from None
    if "samples" not in tables:
        conn.close()
        raise InputError(f"{store} is not a mechopt sample store (it has no samples table)")
    return conn


def store_version(conn: sqlite3.Connection) -> tuple:
    """A cheap signature that changes whenever a run writes a sample or a journal row."""
    samples = conn.execute("SELECT COUNT(*), MAX(id) FROM samples").fetchone()
    runs = [(r.id, r.ended) for r in read_runs(conn)]
    messages = conn.execute("SELECT COUNT(*) FROM run_messages").fetchone() if runs else (0,)
    return (*samples, tuple(runs), *messages)


@dataclass
class StudyData:
    """Everything the store holds about one study (one problem fingerprint).

    Attributes
    ----------
    fingerprint : str
        The problem's fingerprint.
    name : str
        The study's name (from its latest run), or the fingerprint's first characters when no run left a journal.
    runs : list of JournalRun
        Its runs, oldest first.
    records : list of SampleRecord
        Its samples, in the order they were committed.
    messages : list of (str, str)
        The latest run's lines (timestamp, text).
    result : dict
        The latest run's ``result.json``, when its output folder has one for this fingerprint.
    """

    fingerprint: str
    name: str
    runs: list[JournalRun] = field(default_factory=list)
    records: list[SampleRecord] = field(default_factory=list)
    messages: list[tuple[str, str]] = field(default_factory=list)
    result: dict[str, Any] = field(default_factory=dict)

    @property
    def latest(self) -> JournalRun | None:
        """The latest run, or None."""
        return self.runs[-1] if self.runs else None

    @property
    def description(self) -> dict[str, Any]:
        """The latest run's description (:func:`~mechopt.runs.run_journal.describe_run`), else what a
        ``result.json`` says of the problem (a store written before runs kept a journal)."""
        if self.runs:
            return self.runs[-1].description
        problem = self.result.get("problem", {})
        objective = problem.get("objective")
        return {"variables": problem.get("variables", []), "objectives": [objective] if objective else []}


def _result(folder: Path) -> dict[str, Any]:
    try:
        data = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def list_studies(conn: sqlite3.Connection, folder: Path | None = None) -> list[dict[str, Any]]:
    """Every study in the store, most recently started first: fingerprint, name, records, latest run's times.

    Parameters
    ----------
    conn : sqlite3.Connection
        A read-only connection (:func:`open_read_only`).
    folder : Path, optional
        An output folder whose ``result.json`` names its study when no run left a journal.

    Returns
    -------
    list of dict
    """
    result = _result(folder) if folder is not None else {}
    named = {result.get("problem", {}).get("fingerprint"): str(result.get("study"))}
    counts = dict(conn.execute("SELECT fingerprint, COUNT(*) FROM samples GROUP BY fingerprint").fetchall())
    latest: dict[str, JournalRun] = {run.fingerprint: run for run in read_runs(conn)}
    studies = [{"fingerprint": fp, "name": run.name if run else named.get(fp, f"unnamed {fp[:8]}"),
                "records": counts.get(fp, 0), "started": run.started if run else "",
                "ended": run.ended if run else None}
               for fp in {**dict.fromkeys(latest), **dict.fromkeys(counts)}
               for run in [latest.get(fp)]]
    return sorted(studies, key=lambda s: s["started"], reverse=True)


def read_study(conn: sqlite3.Connection, fingerprint: str, folder: Path | None = None) -> StudyData:
    """One study's runs, samples, latest messages and, after its end, its ``result.json``.

    Parameters
    ----------
    conn : sqlite3.Connection
        A read-only connection (:func:`open_read_only`).
    fingerprint : str
        The study's fingerprint (:func:`list_studies`).
    folder : Path, optional
        An output folder whose ``result.json`` is read when no run of the study left a journal.

    Returns
    -------
    StudyData
    """
    runs = [run for run in read_runs(conn) if run.fingerprint == fingerprint]
    where, args = status_filter(fingerprint, None)
    data = StudyData(fingerprint, runs[-1].name if runs else f"unnamed {fingerprint[:8]}", runs,
                     select_rows(conn, where, args))
    if runs:
        data.messages = read_messages(conn, runs[-1].id)
        out = runs[-1].description.get("out")
        folder = Path(out) if isinstance(out, str) else None
    result = _result(folder) if folder is not None else {}
    if result.get("problem", {}).get("fingerprint") == fingerprint:
        data.result = result
        data.name = data.name if runs else str(result.get("study") or data.name)
    return data
