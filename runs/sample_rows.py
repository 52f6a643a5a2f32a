"""The ``samples`` table: records to rows and back, and every query on that table.

Each function runs its statements on the connection it is given; transactions and the translation of SQLite errors
are the caller's (:class:`~mechopt.runs.store_connection.StoreConnection`).
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Sequence

from mechopt.errors import InputError
from mechopt.runs.sample_record import STATUSES, SampleRecord

__all__ = [
    "MAX_KEYS_PER_QUERY",
    "UnreadableRow",
    "count_rows",
    "delete_failed",
    "delete_failed_keys",
    "fingerprint_counts",
    "insert_rows",
    "record_row",
    "select_keys",
    "select_rows",
    "status_filter",
    "stored_statuses",
]

#: SQLite's historical limit on bound parameters is 999; stay below it in IN (...) queries.
MAX_KEYS_PER_QUERY = 500

_COLUMNS = "design, fingerprint, status, outputs, error, wall_time_s, timestamp"


class UnreadableRow(ValueError):
    """A row SQLite reads fine but whose content is not a record (damaged JSON, a hand-edited value)."""


def record_row(record: SampleRecord) -> tuple:
    """The ``samples`` row of a record: (fingerprint, key, design, status, outputs, error, wall_time_s, timestamp).

    Raises
    ------
    InputError
        If an output is not JSON-serializable.
    """
    try:
        outputs = json.dumps(record.outputs, sort_keys=True)
    except (TypeError, ValueError) as exc:
        raise InputError(f"the outputs of design {record.key} are not JSON-serializable: {exc}") from exc
    return (record.fingerprint, record.key, json.dumps(list(record.design)), record.status, outputs, record.error,
            record.wall_time_s, record.timestamp)


def _row_to_record(row: tuple) -> SampleRecord:
    design, fingerprint, status, outputs, error, wall, stamp = row
    try:
        return SampleRecord(
            design=tuple(json.loads(design)),
            fingerprint=fingerprint,
            status=status,
            outputs=json.loads(outputs) if outputs else {},
            error=error,
            wall_time_s=wall,
            timestamp=stamp,
        )
    except (TypeError, ValueError) as exc:
        raise UnreadableRow(f"{exc} in the row of design {design!r:.60}") from exc


def status_filter(fingerprint: str | None, status: str | None) -> tuple[str, list[str]]:
    """The WHERE clause (empty or with a leading space) and its arguments selecting a fingerprint and a status.

    Raises
    ------
    InputError
        If ``status`` is not one of :data:`~mechopt.runs.sample_record.STATUSES`.
    """
    clauses, args = [], []
    if fingerprint is not None:
        clauses.append("fingerprint = ?")
        args.append(fingerprint)
    if status is not None:
        if status not in STATUSES:
            raise InputError(f"status must be one of {', '.join(STATUSES)}, got {status!r}")
        clauses.append("status = ?")
        args.append(status)
    return (" WHERE " + " AND ".join(clauses) if clauses else ""), args


def insert_rows(conn: sqlite3.Connection, rows: Sequence[tuple]) -> int:
    """Insert rows of :func:`record_row`, keeping the stored row of a design already there; number inserted."""
    before = conn.total_changes
    conn.executemany(
        "INSERT OR IGNORE INTO samples (fingerprint, key, design, status, outputs, error, wall_time_s,"
        " timestamp) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
        rows,
    )
    return conn.total_changes - before


def delete_failed(conn: sqlite3.Connection, fingerprint: str) -> int:
    """Delete every ``failed`` row of a fingerprint; number deleted."""
    return conn.execute("DELETE FROM samples WHERE fingerprint = ? AND status = 'failed'", (fingerprint,)).rowcount


def delete_failed_keys(conn: sqlite3.Connection, fingerprint: str, keys: Sequence[str]) -> None:
    """Delete the ``failed`` rows of some design keys of a fingerprint (rows of other statuses are kept)."""
    conn.executemany(
        "DELETE FROM samples WHERE fingerprint = ? AND key = ? AND status = 'failed'",
        [(fingerprint, k) for k in keys],
    )


def stored_statuses(conn: sqlite3.Connection, fingerprint: str, keys: Sequence[str]) -> dict[str, tuple[str, str]]:
    """Key -> (status, timestamp) of the stored rows among at most :data:`MAX_KEYS_PER_QUERY` keys."""
    marks = ",".join("?" * len(keys))
    return {
        key: (status, stamp)
        for key, status, stamp in conn.execute(
            f"SELECT key, status, timestamp FROM samples WHERE fingerprint = ? AND key IN ({marks})",
            [fingerprint, *keys],
        )
    }


def select_keys(conn: sqlite3.Connection, keys: Sequence[str], fingerprint: str) -> dict[str, SampleRecord]:
    """Key -> record of the stored rows among distinct ``keys`` (any number of them).

    Raises
    ------
    UnreadableRow
        If a row found does not hold a valid record.
    """
    found: dict[str, SampleRecord] = {}
    for start in range(0, len(keys), MAX_KEYS_PER_QUERY):
        chunk = keys[start : start + MAX_KEYS_PER_QUERY]
        marks = ",".join("?" * len(chunk))
        rows = conn.execute(
            f"SELECT key, {_COLUMNS} FROM samples WHERE fingerprint = ? AND key IN ({marks})",
            [fingerprint, *chunk],
        ).fetchall()
        for row in rows:
            found[row[0]] = _row_to_record(row[1:])
    return found


def select_rows(conn: sqlite3.Connection, where: str, args: Sequence[str]) -> list[SampleRecord]:
    """The records of the rows matching a :func:`status_filter` clause, in insertion order.

    Raises
    ------
    UnreadableRow
        If a row does not hold a valid record.
    """
    rows = conn.execute(f"SELECT {_COLUMNS} FROM samples{where} ORDER BY id", args).fetchall()
    return [_row_to_record(r) for r in rows]


def count_rows(conn: sqlite3.Connection, where: str, args: Sequence[str]) -> int:
    """Number of rows matching a :func:`status_filter` clause."""
    return conn.execute(f"SELECT COUNT(*) FROM samples{where}", args).fetchone()[0]


def fingerprint_counts(conn: sqlite3.Connection) -> dict[str, int]:
    """Fingerprint -> number of rows, in order of first appearance."""
    query = "SELECT fingerprint, COUNT(*) FROM samples GROUP BY fingerprint ORDER BY MIN(id)"
    return dict(conn.execute(query).fetchall())
