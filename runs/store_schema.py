"""Layout of the sample store's SQLite file: its tables, its version, and the check of what a file holds.

The layout is generic: ``samples`` holds one row per (fingerprint, design key) with the design and the evaluator's
outputs as JSON, ``claims`` the designs runs are evaluating, ``meta`` the schema version and creation time.
"""

from __future__ import annotations

import sqlite3
from pathlib import Path

from mechopt.errors import InputError
from mechopt.runs.sample_record import utc_timestamp

__all__ = ["SCHEMA_VERSION", "create_schema", "holds_current_schema"]

#: Version of the file layout, kept in ``PRAGMA user_version`` and in the ``meta`` table.  Version 1 was mechopt
#: 0.1's four-bar layout (columns oa, ab, bc, t_rms, t_max).
SCHEMA_VERSION = 2

_SCHEMA = (
    """
    CREATE TABLE IF NOT EXISTS meta (
        name  TEXT PRIMARY KEY,
        value TEXT NOT NULL
    )""",
    """
    CREATE TABLE IF NOT EXISTS samples (
        id          INTEGER PRIMARY KEY,
        fingerprint TEXT NOT NULL,
        key         TEXT NOT NULL,
        design      TEXT NOT NULL,
        status      TEXT NOT NULL CHECK (status IN ('ok', 'infeasible', 'failed')),
        outputs     TEXT NOT NULL DEFAULT '{}',
        error       TEXT,
        wall_time_s REAL,
        timestamp   TEXT NOT NULL,
        UNIQUE (fingerprint, key)
    )""",
    """
    CREATE TABLE IF NOT EXISTS claims (
        fingerprint TEXT NOT NULL,
        key         TEXT NOT NULL,
        owner       TEXT NOT NULL,
        expires     REAL NOT NULL,
        PRIMARY KEY (fingerprint, key)
    )""",
    "CREATE INDEX IF NOT EXISTS claims_by_owner ON claims (owner)",
)

_TABLES = {"meta", "samples", "claims"}

_OLD_STORE = (
    "{path} was written by mechopt 0.1 (fixed four-bar columns); move it away or delete it, "
    "its samples will be simulated again"
)


def create_schema(conn: sqlite3.Connection) -> None:
    """Create the tables of an empty store and stamp its version (inside the caller's transaction)."""
    for statement in _SCHEMA:
        conn.execute(statement)
    conn.executemany(
        "INSERT OR REPLACE INTO meta (name, value) VALUES (?, ?)",
        [("schema_version", str(SCHEMA_VERSION)), ("created", utc_timestamp())],
    )
    conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")


def holds_current_schema(conn: sqlite3.Connection, path: Path) -> bool:
    """Whether the file holds the current schema (True) or is empty (False).

    Parameters
    ----------
    conn : sqlite3.Connection
        Open connection to the file.
    path : Path
        The file, for the messages.

    Returns
    -------
    bool

    Raises
    ------
    InputError
        If the file holds anything else: mechopt 0.1's layout, a newer schema, or foreign tables.
    """
    version = conn.execute("PRAGMA user_version").fetchone()[0]
    tables = {row[0] for row in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    columns = {row[1] for row in conn.execute("PRAGMA table_info(samples)")} if "samples" in tables else set()
    if version == 1 or {"oa", "settings_hash"} & columns:
        raise InputError(_OLD_STORE.format(path=path))
    if version > SCHEMA_VERSION:
        raise InputError(
            f"the sample store {path} was written by a newer mechopt (schema {version}, this one reads "
            f"{SCHEMA_VERSION}); upgrade mechopt or use another --store"
        )
    if version == SCHEMA_VERSION and _TABLES <= tables:
        return True
    if tables:
        raise InputError(
            f"{path} is not a mechopt sample store (it holds the tables {', '.join(sorted(tables))}); "
            "give another --store"
        )
    return False
