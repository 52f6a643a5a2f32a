"""Persistent store of simulated designs: one SQLite row per (settings, design), committed when known.

A sampling run can be killed at any moment (Ctrl-C, SIGKILL, a job scheduler's time limit) and restarted:
every result already committed is reused and never simulated again.  The store is a single SQLite file in WAL
mode with a busy timeout, so a second process may read it (or even write to it) while a run is going on.

Designs are identified by a canonical text key, the three lengths in mm rounded to 1e-9 mm, so that float
noise (``0.1 + 0.2`` vs ``0.3``) does not create duplicates.  Rows are also scoped by a ``settings_hash`` (see
:func:`settings_hash`): the same design simulated with other study or engine settings is a different sample.
"""

from __future__ import annotations

import hashlib
import json
import math
import sqlite3
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from mechopt.errors import InputError

__all__ = [
    "KEY_DECIMALS",
    "as_design",
    "STATUSES",
    "SampleRecord",
    "SampleStore",
    "design_key",
    "settings_hash",
]

#: Decimal places (in mm) of the canonical design key: 1e-9 mm is far below any manufacturing tolerance and
#: far above the float noise of lengths of a few hundred mm (~1e-13 mm).
KEY_DECIMALS = 9

#: Allowed values of :attr:`SampleRecord.status`.
STATUSES = ("ok", "infeasible", "failed")

# SQLite's historical limit on bound parameters is 999; stay below it in IN (...) queries.
_CHUNK = 500

_SCHEMA_VERSION = 1

_SCHEMA = """
CREATE TABLE IF NOT EXISTS samples (
    id            INTEGER PRIMARY KEY,
    settings_hash TEXT    NOT NULL,
    key           TEXT    NOT NULL,
    oa            REAL    NOT NULL,
    ab            REAL    NOT NULL,
    bc            REAL    NOT NULL,
    status        TEXT    NOT NULL CHECK (status IN ('ok', 'infeasible', 'failed')),
    t_rms         REAL,
    t_max         REAL,
    extra         TEXT    NOT NULL DEFAULT '{}',
    error         TEXT,
    wall_time_s   REAL,
    timestamp     TEXT    NOT NULL,
    UNIQUE (settings_hash, key)
);
"""

_COLUMNS = "oa, ab, bc, settings_hash, status, t_rms, t_max, extra, error, wall_time_s, timestamp"


def as_design(design: Sequence[float]) -> tuple[float, float, float]:
    """Validate a design and return it as a tuple of three floats.

    Parameters
    ----------
    design : sequence of 3 float
        ``(oa, ab, bc)`` in mm.

    Returns
    -------
    tuple of 3 float

    Raises
    ------
    InputError
        If the design is not three finite numbers.
    """
    try:
        values = tuple(float(x) for x in design)
    except (TypeError, ValueError) as exc:
        raise InputError(f"a design must be three lengths (oa, ab, bc) in mm, got {design!r}") from exc
    if len(values) != 3:
        raise InputError(f"a design must be three lengths (oa, ab, bc) in mm, got {len(values)} values")
    if not all(math.isfinite(x) for x in values):
        raise InputError(f"a design must have finite lengths, got {values!r}")
    return values  # type: ignore[return-value]


def design_key(design: Sequence[float]) -> str:
    """Canonical text key of a design, insensitive to float noise below 1e-9 mm.

    Parameters
    ----------
    design : sequence of 3 float
        ``(oa, ab, bc)`` in mm.

    Returns
    -------
    str
        The three lengths with :data:`KEY_DECIMALS` decimals, comma-separated, e.g.
        ``"100.000000000,250.000000000,180.000000000"``.

    Raises
    ------
    InputError
        If the design is not three finite numbers.
    """
    # ``+ 0.0`` turns -0.0 into 0.0 so that both print the same.
    return ",".join(f"{x + 0.0:.{KEY_DECIMALS}f}" for x in as_design(design))


def _canonical(value: Any) -> Any:
    """Plain JSON value, one spelling per meaning (20 and 20.0 alike, tuples as lists, numpy as Python)."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise InputError(f"settings must be finite numbers, got {value!r}")
        # A TOML "20" and "20.0" mean the same setting; hash them alike (exactly representable integers only).
        if value.is_integer() and abs(value) < 2.0**53:
            return int(value)
        return value
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise InputError(f"settings keys must be strings, got {k!r}")
            out[k] = _canonical(v)
        return out
    if isinstance(value, list | tuple):
        return [_canonical(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "tolist"):  # numpy scalars and arrays, without importing numpy here
        return _canonical(value.tolist())
    raise InputError(f"settings must be JSON-like (numbers, strings, lists, dicts), got {type(value).__name__}")


def settings_hash(settings: dict[str, Any]) -> str:
    """Hash of the study and engine settings that a sample depends on.

    The settings are written as canonical JSON (sorted keys, no spaces, integral floats as integers, tuples as
    lists, numpy values as Python values) and hashed with SHA-256, so that the same settings always give the
    same hash whatever the key order or the spelling ``20`` / ``20.0``.

    Parameters
    ----------
    settings : dict
        JSON-like mapping of everything that changes a simulated result (mechanism, load, motion law, engine,
        time step...).  Keep out of it what does not change results (number of workers, output paths).

    Returns
    -------
    str
        64 hexadecimal characters.

    Raises
    ------
    InputError
        If a value is not finite or not JSON-like.
    """
    if not isinstance(settings, dict):
        raise InputError(f"settings must be a dict, got {type(settings).__name__}")
    text = json.dumps(_canonical(settings), sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="milliseconds").replace("+00:00", "Z")


@dataclass(frozen=True)
class SampleRecord:
    """One simulated design.

    Attributes
    ----------
    oa, ab, bc : float
        The design in mm, as first requested (float noise below 1e-9 mm maps to the same :attr:`key`).
    settings_hash : str
        Hash of the settings the design was simulated with (:func:`settings_hash`).
    status : str
        ``"ok"``, ``"infeasible"`` (the simulator raised ``InfeasibleDesignError``) or ``"failed"`` (any other
        error).
    t_rms, t_max : float or None
        RMS and peak input torque over one cycle in N·m; ``None`` unless ``status == "ok"``.
    extra : dict
        Further JSON-able outputs of the simulator.
    error : str or None
        One-line message of the error for ``infeasible`` and ``failed`` records.
    wall_time_s : float or None
        Wall time of the simulator call, measured in the worker.
    timestamp : str
        ISO 8601 UTC time when the result was known.
    """

    oa: float
    ab: float
    bc: float
    settings_hash: str
    status: str
    t_rms: float | None = None
    t_max: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    error: str | None = None
    wall_time_s: float | None = None
    timestamp: str = field(default_factory=_now)

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise InputError(f"status must be one of {', '.join(STATUSES)}, got {self.status!r}")
        if self.status == "ok":
            for name in ("t_rms", "t_max"):
                value = getattr(self, name)
                if value is None or not math.isfinite(value):
                    raise InputError(f"an 'ok' record needs a finite {name}, got {value!r}")

    @property
    def design(self) -> tuple[float, float, float]:
        """The design ``(oa, ab, bc)`` in mm."""
        return (self.oa, self.ab, self.bc)

    @property
    def key(self) -> str:
        """Canonical key of the design (:func:`design_key`)."""
        return design_key(self.design)

    @property
    def ok(self) -> bool:
        """Whether the simulation succeeded."""
        return self.status == "ok"

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict of the record (for ``result.json`` and reports).

        Returns
        -------
        dict
            All attributes plus ``key``.
        """
        return {
            "oa": self.oa,
            "ab": self.ab,
            "bc": self.bc,
            "key": self.key,
            "settings_hash": self.settings_hash,
            "status": self.status,
            "t_rms": self.t_rms,
            "t_max": self.t_max,
            "extra": dict(self.extra),
            "error": self.error,
            "wall_time_s": self.wall_time_s,
            "timestamp": self.timestamp,
        }


def _row_to_record(row: tuple) -> SampleRecord:
    oa, ab, bc, shash, status, t_rms, t_max, extra, error, wall, stamp = row
    return SampleRecord(
        oa=oa,
        ab=ab,
        bc=bc,
        settings_hash=shash,
        status=status,
        t_rms=t_rms,
        t_max=t_max,
        extra=json.loads(extra) if extra else {},
        error=error,
        wall_time_s=wall,
        timestamp=stamp,
    )


class SampleStore:
    """SQLite file of simulated designs; reuse across runs, safe to kill at any time.

    Each :meth:`put` is its own committed transaction, so a run killed even with SIGKILL keeps every result it
    had written.  The file is in WAL mode with a busy timeout, so other processes can read it during a run and
    concurrent writers wait for each other instead of failing.

    Parameters
    ----------
    path : str or Path
        The database file; created with its parent directories if missing.
    timeout : float, optional
        Seconds to wait for a lock held by another process before giving up (default 30).

    Raises
    ------
    InputError
        If the file exists but is not a SQLite database, or cannot be opened.

    Examples
    --------
    >>> with SampleStore(tmp / "samples.sqlite") as store:  # doctest: +SKIP
    ...     todo = store.missing(designs, h)
    """

    def __init__(self, path: str | Path, *, timeout: float = 30.0) -> None:
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            # Autocommit mode: every statement outside an explicit BEGIN is its own committed transaction.
            self._conn: sqlite3.Connection | None = sqlite3.connect(self.path, timeout=timeout, isolation_level=None)
        except (OSError, sqlite3.Error) as exc:
            raise InputError(f"cannot open the sample store {self.path}: {exc}") from exc
        try:
            self._set_up(timeout)
        except sqlite3.DatabaseError as exc:
            self.close()
            raise InputError(f"{self.path} is not a usable sample store: {exc}") from exc
        except BaseException:
            self.close()
            raise

    def _set_up(self, timeout: float) -> None:
        """WAL mode and the schema, retried while another process is doing the same to a new file.

        Switching a fresh database into WAL mode takes an exclusive lock and SQLite may report SQLITE_BUSY at once,
        without waiting on the busy timeout, when two processes open the same new file together.
        """
        conn = self._c
        deadline = time.monotonic() + timeout
        delay = 0.005
        while True:
            try:
                # WAL lets readers (a progress monitor, a second study) work while the run writes.
                conn.execute("PRAGMA journal_mode = WAL")
                # In WAL mode NORMAL loses no committed transaction when the *process* dies (only on power loss),
                # and avoids an fsync per result.
                conn.execute("PRAGMA synchronous = NORMAL")
                with self._transaction():
                    version = conn.execute("PRAGMA user_version").fetchone()[0]
                    if version > _SCHEMA_VERSION:
                        raise InputError(
                            f"the sample store {self.path} was written by a newer mechopt (schema {version})"
                        )
                    conn.execute(_SCHEMA)
                    if version < _SCHEMA_VERSION:
                        conn.execute(f"PRAGMA user_version = {_SCHEMA_VERSION}")
                return
            except sqlite3.OperationalError as exc:
                if "locked" not in str(exc) or time.monotonic() > deadline:
                    raise
                time.sleep(delay)
                delay = min(2 * delay, 0.2)

    # -- plumbing -------------------------------------------------------------------------------------------

    @property
    def _c(self) -> sqlite3.Connection:
        if self._conn is None:
            raise InputError(f"the sample store {self.path} is closed")
        return self._conn

    def _transaction(self) -> _Transaction:
        return _Transaction(self._c)

    def close(self) -> None:
        """Close the database connection (idempotent)."""
        if self._conn is not None:
            self._conn.close()
            self._conn = None

    def __enter__(self) -> SampleStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"SampleStore({str(self.path)!r})"

    # -- writing --------------------------------------------------------------------------------------------

    def put(self, record: SampleRecord) -> bool:
        """Store one record and commit it.

        Parameters
        ----------
        record : SampleRecord
            The result of one simulation.

        Returns
        -------
        bool
            True if stored; False if the store already had this design for this settings hash (the stored row
            is kept: a design is never simulated, nor stored, twice).
        """
        return self.put_many([record]) == 1

    def put_many(self, records: Iterable[SampleRecord]) -> int:
        """Store several records in one committed transaction (duplicates are ignored, as in :meth:`put`).

        Parameters
        ----------
        records : iterable of SampleRecord
            Results to store.

        Returns
        -------
        int
            Number of records actually inserted.
        """
        rows = [
            (
                r.settings_hash,
                r.key,
                r.oa,
                r.ab,
                r.bc,
                r.status,
                r.t_rms,
                r.t_max,
                json.dumps(r.extra, sort_keys=True),
                r.error,
                r.wall_time_s,
                r.timestamp,
            )
            for r in records
        ]
        if not rows:
            return 0
        conn = self._c
        with self._transaction():
            before = conn.total_changes
            conn.executemany(
                "INSERT OR IGNORE INTO samples (settings_hash, key, oa, ab, bc, status, t_rms, t_max, extra,"
                " error, wall_time_s, timestamp) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                rows,
            )
            return conn.total_changes - before

    # -- reading --------------------------------------------------------------------------------------------

    def get(self, design: Sequence[float], settings_hash: str) -> SampleRecord | None:
        """The stored record of one design, or None.

        Parameters
        ----------
        design : sequence of 3 float
            ``(oa, ab, bc)`` in mm.
        settings_hash : str
            Settings the record must have been simulated with.

        Returns
        -------
        SampleRecord or None
        """
        return self.get_many([design], settings_hash).get(design_key(design))

    def get_many(self, designs: Iterable[Sequence[float]], settings_hash: str) -> dict[str, SampleRecord]:
        """The stored records of several designs.

        Parameters
        ----------
        designs : iterable of sequences of 3 float
            Designs ``(oa, ab, bc)`` in mm; duplicates are fine.
        settings_hash : str
            Settings the records must have been simulated with.

        Returns
        -------
        dict
            Design key (:func:`design_key`) → record, for the designs found.
        """
        keys = list(dict.fromkeys(design_key(d) for d in designs))
        found: dict[str, SampleRecord] = {}
        conn = self._c
        for start in range(0, len(keys), _CHUNK):
            chunk = keys[start : start + _CHUNK]
            marks = ",".join("?" * len(chunk))
            rows = conn.execute(
                f"SELECT key, {_COLUMNS} FROM samples WHERE settings_hash = ? AND key IN ({marks})",
                [settings_hash, *chunk],
            ).fetchall()
            for row in rows:
                found[row[0]] = _row_to_record(row[1:])
        return found

    def missing(self, designs: Iterable[Sequence[float]], settings_hash: str) -> list[tuple[float, float, float]]:
        """Designs not yet stored for these settings, deduplicated by key, in first-seen order.

        Parameters
        ----------
        designs : iterable of sequences of 3 float
            Designs ``(oa, ab, bc)`` in mm.
        settings_hash : str
            Settings hash of the run.

        Returns
        -------
        list of tuple
            The designs still to simulate (failed and infeasible records count as stored).
        """
        unique: dict[str, tuple[float, float, float]] = {}
        for d in designs:
            unique.setdefault(design_key(d), as_design(d))
        stored = self.get_many(unique.values(), settings_hash)
        return [d for k, d in unique.items() if k not in stored]

    def records(self, settings_hash: str | None = None, status: str | None = None) -> list[SampleRecord]:
        """All stored records, in insertion order.

        Parameters
        ----------
        settings_hash : str, optional
            Only the records of these settings.
        status : str, optional
            Only the records with this status.

        Returns
        -------
        list of SampleRecord
        """
        where, args = self._filter(settings_hash, status)
        rows = self._c.execute(f"SELECT {_COLUMNS} FROM samples{where} ORDER BY id", args).fetchall()
        return [_row_to_record(r) for r in rows]

    def count(self, settings_hash: str | None = None, status: str | None = None) -> int:
        """Number of stored records.

        Parameters
        ----------
        settings_hash : str, optional
            Only the records of these settings.
        status : str, optional
            Only the records with this status.

        Returns
        -------
        int
        """
        where, args = self._filter(settings_hash, status)
        return self._c.execute(f"SELECT COUNT(*) FROM samples{where}", args).fetchone()[0]

    def settings_hashes(self) -> dict[str, int]:
        """Settings hashes present in the store with their number of records.

        Returns
        -------
        dict
            settings hash → number of records.
        """
        query = "SELECT settings_hash, COUNT(*) FROM samples GROUP BY settings_hash"
        return dict(self._c.execute(query).fetchall())

    @staticmethod
    def _filter(settings_hash: str | None, status: str | None) -> tuple[str, list[str]]:
        clauses, args = [], []
        if settings_hash is not None:
            clauses.append("settings_hash = ?")
            args.append(settings_hash)
        if status is not None:
            if status not in STATUSES:
                raise InputError(f"status must be one of {', '.join(STATUSES)}, got {status!r}")
            clauses.append("status = ?")
            args.append(status)
        return (" WHERE " + " AND ".join(clauses) if clauses else ""), args


class _Transaction:
    """``BEGIN IMMEDIATE`` … ``COMMIT`` (or ``ROLLBACK``) on an autocommit connection.

    IMMEDIATE takes the write lock up front, so a concurrent writer waits on the busy timeout at BEGIN instead
    of failing later with SQLITE_BUSY on a lock upgrade that the timeout cannot resolve.
    """

    def __init__(self, conn: sqlite3.Connection) -> None:
        self._conn = conn

    def __enter__(self) -> None:
        self._conn.execute("BEGIN IMMEDIATE")

    def __exit__(self, exc_type: object, *rest: object) -> None:
        self._conn.execute("COMMIT" if exc_type is None else "ROLLBACK")
