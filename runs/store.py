"""Persistent store of evaluated designs: one SQLite row per (fingerprint, design), committed when known.

The store knows nothing of any mechanism: a row holds a design (a tuple of d >= 1 floats), the fingerprint of the
problem and settings it was evaluated with, a status and whatever the evaluator returned (JSON).  As in Optuna, the
storage lives apart from the study that fills it: several studies, problems and runs may share one file.

A sampling run can be killed at any moment (Ctrl-C, SIGKILL, a scheduler's time limit) and restarted: every result
already committed is reused and never evaluated again.  The file is in WAL mode with a busy timeout, so other
processes read it (or write to it) while a run is going on.

Designs are identified by a canonical text key, the values rounded to 1e-9 in the variables' units, so that float
noise (``0.1 + 0.2`` vs ``0.3``) does not create duplicates.

Claims (table ``claims``) let concurrent runs on one file share the work instead of each evaluating everything: a run
claims the designs it is about to evaluate, with a lease it renews while alive; another run leaves validly claimed
designs alone and waits for their results, and takes a claim over once its lease has expired (or, on the same host,
as soon as the claiming process is gone).
"""

from __future__ import annotations

import json
import math
import os
import socket
import sqlite3
import tempfile
import time
import uuid
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import UTC, datetime
from itertools import islice
from pathlib import Path
from typing import Any
from urllib.parse import quote

from mechopt.errors import InputError

__all__ = [
    "KEY_DECIMALS",
    "SCHEMA_VERSION",
    "STATUSES",
    "Claim",
    "SampleRecord",
    "SampleStore",
    "as_design",
    "design_key",
    "new_owner",
    "utc_timestamp",
]

#: Decimal places of the canonical design key: 1e-9 (mm, rad...) is far below any manufacturing tolerance and far
#: above the float noise of values of a few hundred units (~1e-13).
KEY_DECIMALS = 9

#: Allowed values of :attr:`SampleRecord.status`.
STATUSES = ("ok", "infeasible", "failed")

#: Version of the file layout, kept in ``PRAGMA user_version`` and in the ``meta`` table.  Version 1 was mechopt
#: 0.1's four-bar layout (columns oa, ab, bc, t_rms, t_max).
SCHEMA_VERSION = 2

# SQLite's historical limit on bound parameters is 999; stay below it in IN (...) queries.
_CHUNK = 500

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

_COLUMNS = "design, fingerprint, status, outputs, error, wall_time_s, timestamp"

_OLD_STORE = (
    "{path} was written by mechopt 0.1 (fixed four-bar columns); move it away or delete it, "
    "its samples will be simulated again"
)

# Primary SQLite result codes (sqlite3.Error.sqlite_errorcode & 0xFF).
_BUSY, _LOCKED, _READONLY, _IOERR, _CORRUPT, _FULL, _CANTOPEN, _NOTADB = 5, 6, 8, 10, 11, 13, 14, 26


def as_design(design: Sequence[float], dim: int | None = None) -> tuple[float, ...]:
    """Validate a design and return it as a tuple of floats.

    Parameters
    ----------
    design : sequence of float
        The design variables, in their units (mm, rad...).
    dim : int, optional
        Required number of values; any number >= 1 if omitted.

    Returns
    -------
    tuple of float

    Raises
    ------
    InputError
        If the design is not a non-empty sequence of finite numbers (of length ``dim`` when given).
    """
    try:
        values = tuple(float(x) for x in design)
    except (TypeError, ValueError) as exc:
        raise InputError(f"a design must be a sequence of numbers, got {design!r:.80}") from exc
    if not values:
        raise InputError("a design must have at least one value, got none")
    if dim is not None and len(values) != dim:
        raise InputError(f"a design must have {dim} values, got {len(values)}: {values!r:.80}")
    if not all(math.isfinite(x) for x in values):
        raise InputError(f"a design must have finite values, got {values!r:.80}")
    return values


def design_key(design: Sequence[float]) -> str:
    """Canonical text key of a design, insensitive to float noise below 1e-9.

    Parameters
    ----------
    design : sequence of float
        Any number d >= 1 of values, in the variables' units.

    Returns
    -------
    str
        The values with :data:`KEY_DECIMALS` decimals, comma-separated, e.g. ``"100.000000000,250.000000000"``.

    Raises
    ------
    InputError
        If the design is not a non-empty sequence of finite numbers.
    """
    # ``+ 0.0`` turns -0.0 into 0.0 so that both print the same.
    return ",".join(f"{x + 0.0:.{KEY_DECIMALS}f}" for x in as_design(design))


def new_owner() -> str:
    """A claim owner id unique to one call: ``"HOST/PID/UUID"``.

    The host and process id let a run on the same host take over at once the claims of a process that is gone
    (killed with SIGKILL), instead of waiting for their leases to expire.
    """
    return f"{socket.gethostname()}/{os.getpid()}/{uuid.uuid4().hex}"


def _owner_is_gone(owner: str) -> bool:
    """Whether ``owner`` (:func:`new_owner`) names a process of this host that no longer exists."""
    host, _, rest = owner.partition("/")
    pid_text = rest.partition("/")[0]
    if host != socket.gethostname() or not pid_text.isdigit():
        return False  # another host (or a foreign id): only its lease tells
    try:
        os.kill(int(pid_text), 0)
    except ProcessLookupError:
        return True
    except OSError:
        return False  # exists, owned by another user
    return False


def utc_timestamp() -> str:
    """Now as an ISO 8601 UTC timestamp with milliseconds, e.g. ``2026-01-31T12:00:00.123Z`` (sorts as text)."""
    return datetime.now(UTC).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


@dataclass(frozen=True)
class SampleRecord:
    """One evaluated design.

    Attributes
    ----------
    design : tuple of float
        The design as first requested, in the variables' units (float noise below 1e-9 maps to the same
        :attr:`key`).
    fingerprint : str
        Hash of the problem and settings the design was evaluated with (``DesignProblem.fingerprint()``).
    status : str
        ``"ok"``, ``"infeasible"`` (the evaluator raised ``InfeasibleDesignError``) or ``"failed"`` (any other
        error, or an unusable return value).
    outputs : dict
        Everything the evaluator returned (JSON values); empty unless ``status == "ok"``.
    error : str or None
        One-line message for ``infeasible`` and ``failed`` records.
    wall_time_s : float or None
        Wall time of the evaluator call in s, measured in the worker.
    timestamp : str
        ISO 8601 UTC time when the result was known.
    """

    design: tuple[float, ...]
    fingerprint: str
    status: str
    outputs: dict[str, Any] = field(default_factory=dict)
    error: str | None = None
    wall_time_s: float | None = None
    timestamp: str = field(default_factory=utc_timestamp)

    def __post_init__(self) -> None:
        object.__setattr__(self, "design", as_design(self.design))
        if self.status not in STATUSES:
            raise InputError(f"status must be one of {', '.join(STATUSES)}, got {self.status!r}")
        if not isinstance(self.fingerprint, str) or not self.fingerprint:
            raise InputError(f"a record needs a fingerprint string, got {self.fingerprint!r}")
        if not isinstance(self.outputs, dict):
            raise InputError(f"outputs must be a dict, got {type(self.outputs).__name__}")
        if self.outputs and self.status != "ok":
            raise InputError(f"a {self.status!r} record has no outputs, got {sorted(self.outputs)}")

    @property
    def key(self) -> str:
        """Canonical key of the design (:func:`design_key`)."""
        return design_key(self.design)

    @property
    def ok(self) -> bool:
        """Whether the evaluation succeeded."""
        return self.status == "ok"

    def value(self, name: str) -> float:
        """One output as a float.

        Parameters
        ----------
        name : str
            Output name, e.g. ``"t_rms"``.

        Returns
        -------
        float
            The output, in the evaluator's unit; NaN unless the record is ``ok`` and has a numeric output ``name``.
        """
        if not self.ok:
            return math.nan
        value = self.outputs.get(name)
        if isinstance(value, bool) or not isinstance(value, int | float):
            return math.nan
        return float(value)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict of the record (for ``result.json`` and reports).

        Returns
        -------
        dict
            All attributes, the design as a list, plus ``key``.
        """
        return {
            "design": list(self.design),
            "key": self.key,
            "fingerprint": self.fingerprint,
            "status": self.status,
            "outputs": dict(self.outputs),
            "error": self.error,
            "wall_time_s": self.wall_time_s,
            "timestamp": self.timestamp,
        }


@dataclass(frozen=True)
class Claim:
    """A design a run is evaluating: other runs leave it alone until ``expires`` (s since the epoch, UTC)."""

    fingerprint: str
    key: str
    owner: str
    expires: float


class SampleStore:
    """SQLite file of evaluated designs; reused across runs and studies, safe to kill at any time.

    Each :meth:`put` is its own committed transaction, so a run killed even with SIGKILL keeps every result it had
    written.  The file is in WAL mode with a busy timeout, so other processes read it during a run and concurrent
    writers wait for each other instead of failing.  A file (or folder) that is not writable is opened read-only:
    reading works and writing raises a one-line :class:`InputError`.

    Parameters
    ----------
    path : str or Path
        The database file; created with its parent folders if missing.
    timeout : float, optional
        Seconds to wait for a lock held by another process before giving up (default 30).

    Raises
    ------
    InputError
        If the file is not a SQLite database, is corrupt, was written by another version of mechopt, or cannot be
        created.  Every SQLite error of a later call is also turned into a one-line :class:`InputError`.

    Examples
    --------
    >>> with SampleStore(tmp / "samples.sqlite") as store:  # doctest: +SKIP
    ...     todo = store.missing(designs, problem.fingerprint())
    """

    def __init__(self, path: str | Path, *, timeout: float = 30.0) -> None:
        self.path = Path(path)
        self.timeout = float(timeout)
        self._conn: sqlite3.Connection | None = None
        #: Why the store cannot be written to (None if it can).
        self.read_only: str | None = None
        existed = self.path.exists()
        if existed and not self.path.is_file():
            raise InputError(f"the sample store {self.path} is not a file")
        try:
            self._open_read_write(existed)
        except sqlite3.DatabaseError as exc:
            self.close()
            code = _code(exc)
            if existed and code in (_READONLY, _CANTOPEN):
                self._open_read_only()
            elif not existed and code in (_READONLY, _CANTOPEN):
                raise InputError(f"cannot create the sample store {self.path}: {_why_read_only(self.path)}") from exc
            else:
                raise self._error(exc, "opening it") from exc
        except BaseException:
            self.close()
            raise

    # -- opening ------------------------------------------------------------------------------------------------

    def _open_read_write(self, existed: bool) -> None:
        if not existed:
            try:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise InputError(f"cannot create the folder of the sample store {self.path}: {exc}") from exc
        # Autocommit mode: every statement outside an explicit BEGIN is its own committed transaction.
        self._conn = sqlite3.connect(self.path, timeout=self.timeout, isolation_level=None)
        conn = self._conn
        deadline = time.monotonic() + self.timeout
        delay = 0.005
        while True:
            # Switching a fresh database into WAL mode takes an exclusive lock and SQLite may report SQLITE_BUSY at
            # once, without waiting on the busy timeout, when several processes open the same new file together.
            try:
                # WAL lets readers (a progress monitor, a second study) work while a run writes.
                conn.execute("PRAGMA journal_mode = WAL")
                # In WAL mode NORMAL loses no committed transaction when the *process* dies (only on power loss),
                # and avoids an fsync per result.
                conn.execute("PRAGMA synchronous = NORMAL")
                if self._check_schema():
                    return
                with self._transaction():
                    if self._check_schema():
                        return
                    for statement in _SCHEMA:
                        conn.execute(statement)
                    conn.executemany(
                        "INSERT OR REPLACE INTO meta (name, value) VALUES (?, ?)",
                        [("schema_version", str(SCHEMA_VERSION)), ("created", utc_timestamp())],
                    )
                    conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
                return
            except sqlite3.OperationalError as exc:
                if _code(exc) not in (_BUSY, _LOCKED) or time.monotonic() > deadline:
                    raise
                time.sleep(delay)
                delay = min(2 * delay, 0.2)

    def _open_read_only(self) -> None:
        """Open a store that cannot be written: its file, or its folder (no room for the WAL files), is read-only."""
        self.read_only = _why_read_only(self.path)
        uri = "file:" + quote(str(self.path.resolve()))
        # mode=ro reads a WAL file whose -wal/-shm exist or can be created; in a read-only folder they cannot, and
        # only immutable=1 opens it — safe there, since no writer can create the WAL it would need either.
        for suffix in ("?mode=ro", "?immutable=1"):
            try:
                self._conn = sqlite3.connect(uri + suffix, uri=True, timeout=self.timeout, isolation_level=None)
                if not self._check_schema():
                    raise InputError(f"the sample store {self.path} is empty and {self.read_only}")
                return
            except sqlite3.DatabaseError as exc:
                self.close()
                if _code(exc) == _CANTOPEN and suffix != "?immutable=1":
                    continue
                raise self._error(exc, "opening it read-only") from exc
            except BaseException:
                self.close()
                raise

    def _check_schema(self) -> bool:
        """True if the file holds the current schema, False if it is empty; InputError if it holds anything else."""
        conn = self._c
        version = conn.execute("PRAGMA user_version").fetchone()[0]
        tables = {row[0] for row in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        columns = {row[1] for row in conn.execute("PRAGMA table_info(samples)")} if "samples" in tables else set()
        if version == 1 or {"oa", "settings_hash"} & columns:
            raise InputError(_OLD_STORE.format(path=self.path))
        if version > SCHEMA_VERSION:
            raise InputError(
                f"the sample store {self.path} was written by a newer mechopt (schema {version}, this one reads "
                f"{SCHEMA_VERSION}); upgrade mechopt or use another --store"
            )
        if version == SCHEMA_VERSION and _TABLES <= tables:
            return True
        if tables:
            raise InputError(
                f"{self.path} is not a mechopt sample store (it holds the tables {', '.join(sorted(tables))}); "
                "give another --store"
            )
        return False

    # -- plumbing -----------------------------------------------------------------------------------------------

    @property
    def _c(self) -> sqlite3.Connection:
        if self._conn is None:
            raise InputError(f"the sample store {self.path} is closed")
        return self._conn

    def _transaction(self) -> _Transaction:
        return _Transaction(self._c)

    def _error(self, exc: sqlite3.DatabaseError, doing: str) -> InputError:
        """The one-line error a user sees for an SQLite error while ``doing`` something."""
        code = _code(exc)
        detail = _one_line(str(exc))
        if code in (_BUSY, _LOCKED):
            return InputError(
                f"the sample store {self.path} is locked by another process (waited {self.timeout:g} s while "
                f"{doing}); try again when it is done"
            )
        if code == _READONLY:
            return InputError(f"cannot write to the sample store {self.path}: {_why_read_only(self.path)}")
        if code == _FULL:
            return InputError(f"the disk of the sample store {self.path} is full ({doing})")
        if code == _CANTOPEN:
            return InputError(f"cannot open the sample store {self.path}: {detail}")
        if code == _IOERR:
            return InputError(f"cannot read or write the sample store {self.path} ({detail} while {doing})")
        return InputError(
            f"{self.path} is not a usable sample store ({detail} while {doing}); move it away or delete it, "
            "its samples will be simulated again"
        )

    @contextmanager
    def _sql(self, doing: str, write: bool = False) -> Iterator[sqlite3.Connection]:
        """The connection, with every SQLite error (a corrupt page met mid-file included) turned into one line."""
        if write and self.read_only:
            raise InputError(f"cannot write to the sample store {self.path}: {self.read_only}")
        conn = self._c
        try:
            yield conn
        except sqlite3.DatabaseError as exc:
            raise self._error(exc, doing) from exc
        except _BadRow as exc:
            raise InputError(
                f"{self.path} is not a usable sample store (unreadable row: {_one_line(str(exc))}); move it away "
                "or delete it, its samples will be simulated again"
            ) from exc

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
        return f"SampleStore({str(self.path)!r}{', read-only' if self.read_only else ''})"

    # -- writing ------------------------------------------------------------------------------------------------

    def put(self, record: SampleRecord) -> bool:
        """Store one record and commit it; any claim on its design is dropped in the same transaction.

        Parameters
        ----------
        record : SampleRecord
            The result of one evaluation.

        Returns
        -------
        bool
            True if stored; False if the store already had this design for this fingerprint (the stored row is
            kept: a design is never evaluated, nor stored, twice).

        Raises
        ------
        InputError
            If the store is read-only or an output is not JSON-serializable.
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
        rows = []
        for r in records:
            try:
                outputs = json.dumps(r.outputs, sort_keys=True)
            except (TypeError, ValueError) as exc:
                raise InputError(f"the outputs of design {r.key} are not JSON-serializable: {exc}") from exc
            rows.append((r.fingerprint, r.key, json.dumps(list(r.design)), r.status, outputs, r.error,
                         r.wall_time_s, r.timestamp))
        if not rows:
            return 0
        with self._sql("storing results", write=True) as conn, self._transaction():
            before = conn.total_changes
            conn.executemany(
                "INSERT OR IGNORE INTO samples (fingerprint, key, design, status, outputs, error, wall_time_s,"
                " timestamp) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                rows,
            )
            inserted = conn.total_changes - before
            conn.executemany("DELETE FROM claims WHERE fingerprint = ? AND key = ?", [r[:2] for r in rows])
            return inserted

    def forget_failed(self, fingerprint: str) -> int:
        """Delete the ``failed`` records of a fingerprint, so that they are evaluated again.

        Parameters
        ----------
        fingerprint : str
            Fingerprint whose failures are forgotten (``ok`` and ``infeasible`` records are kept).

        Returns
        -------
        int
            Number of records deleted.
        """
        with self._sql("deleting failed records", write=True) as conn, self._transaction():
            return conn.execute(
                "DELETE FROM samples WHERE fingerprint = ? AND status = 'failed'", (fingerprint,)
            ).rowcount

    # -- claims -------------------------------------------------------------------------------------------------

    def claim(
        self,
        fingerprint: str,
        keys: Iterable[str],
        owner: str,
        lease_s: float,
        *,
        limit: int | None = None,
        redo_failed_before: str | None = None,
    ) -> list[str]:
        """Claim designs to evaluate, in one transaction: those neither stored nor validly claimed by another owner.

        A claim of another owner is valid until its lease expires, or, on this host, until its process is gone.

        Parameters
        ----------
        fingerprint : str
            Fingerprint of the run.
        keys : iterable of str
            Design keys (:func:`design_key`) in order of preference; read lazily, only as far as needed to claim
            ``limit`` of them.
        owner : str
            This run's owner id (:func:`new_owner`); its own claims are renewed (and returned).
        lease_s : float
            Seconds the claims stay valid unless renewed (:meth:`renew_claims`).
        limit : int, optional
            Claim at most this many (the first claimable ones in ``keys``).
        redo_failed_before : str, optional
            ISO timestamp: a ``failed`` record written before it counts as not stored; when its design is claimed
            the record is deleted (it is evaluated again and replaced).

        Returns
        -------
        list of str
            The keys now claimed by ``owner``, in the order of ``keys``.
        """
        if isinstance(lease_s, bool) or not isinstance(lease_s, int | float) or not lease_s > 0:
            raise InputError(f"lease_s must be a positive number of seconds, got {lease_s!r}")
        if limit is not None and limit < 1:
            return []
        todo = _unique(keys)
        # Without contention the first few keys are claimable: look at a few, then at more and more.
        size = _CHUNK if limit is None else min(_CHUNK, max(32, 2 * limit))
        taken: list[str] = []
        with self._sql("claiming designs", write=True) as conn, self._transaction():
            now = time.time()
            gone: dict[str, bool] = {}
            while limit is None or len(taken) < limit:
                chunk = list(islice(todo, size))
                if not chunk:
                    break
                size = min(2 * size, _CHUNK)
                marks = ",".join("?" * len(chunk))
                args = [fingerprint, *chunk]
                stored = {
                    key: (status, stamp)
                    for key, status, stamp in conn.execute(
                        f"SELECT key, status, timestamp FROM samples WHERE fingerprint = ? AND key IN ({marks})", args
                    )
                }
                held = {
                    key: (who, expires)
                    for key, who, expires in conn.execute(
                        f"SELECT key, owner, expires FROM claims WHERE fingerprint = ? AND key IN ({marks})", args
                    )
                }
                redo = []
                for key in chunk:
                    if limit is not None and len(taken) >= limit:
                        break
                    if key in stored:
                        status, stamp = stored[key]
                        if not (redo_failed_before and status == "failed" and stamp < redo_failed_before):
                            continue
                    if key in held:
                        who, expires = held[key]
                        if who != owner and expires > now:
                            if who not in gone:
                                gone[who] = _owner_is_gone(who)
                            if not gone[who]:
                                continue
                    taken.append(key)
                    if key in stored:
                        redo.append(key)
                conn.executemany(
                    "DELETE FROM samples WHERE fingerprint = ? AND key = ? AND status = 'failed'",
                    [(fingerprint, k) for k in redo],
                )
            conn.executemany(
                "INSERT OR REPLACE INTO claims (fingerprint, key, owner, expires) VALUES (?, ?, ?, ?)",
                [(fingerprint, k, owner, now + lease_s) for k in taken],
            )
        return taken

    def renew_claims(self, owner: str, lease_s: float) -> int:
        """Extend every claim of ``owner`` to ``lease_s`` seconds from now (the heartbeat of a live run).

        Returns
        -------
        int
            Number of claims renewed.
        """
        with self._sql("renewing claims", write=True) as conn, self._transaction():
            return conn.execute(
                "UPDATE claims SET expires = ? WHERE owner = ?", (time.time() + lease_s, owner)
            ).rowcount

    def release_claims(self, owner: str, keys: Iterable[str] | None = None) -> int:
        """Drop claims of ``owner``: all of them, or those of ``keys``.

        Returns
        -------
        int
            Number of claims dropped.
        """
        with self._sql("releasing claims", write=True) as conn, self._transaction():
            if keys is None:
                return conn.execute("DELETE FROM claims WHERE owner = ?", (owner,)).rowcount
            before = conn.total_changes
            conn.executemany("DELETE FROM claims WHERE owner = ? AND key = ?", [(owner, k) for k in keys])
            return conn.total_changes - before

    def claims(self, fingerprint: str | None = None) -> list[Claim]:
        """Current claims (valid or expired), oldest lease end first.

        Parameters
        ----------
        fingerprint : str, optional
            Only the claims of this fingerprint.

        Returns
        -------
        list of Claim
        """
        where, args = ("WHERE fingerprint = ?", [fingerprint]) if fingerprint is not None else ("", [])
        with self._sql("reading claims") as conn:
            rows = conn.execute(
                f"SELECT fingerprint, key, owner, expires FROM claims {where} ORDER BY expires, key", args
            ).fetchall()
        return [Claim(*row) for row in rows]

    # -- reading ------------------------------------------------------------------------------------------------

    def get(self, design: Sequence[float], fingerprint: str) -> SampleRecord | None:
        """The stored record of one design, or None.

        Parameters
        ----------
        design : sequence of float
            The design, in the variables' units.
        fingerprint : str
            Fingerprint the record must have been evaluated with.

        Returns
        -------
        SampleRecord or None
        """
        return self.get_many([design], fingerprint).get(design_key(design))

    def get_many(self, designs: Iterable[Sequence[float]], fingerprint: str) -> dict[str, SampleRecord]:
        """The stored records of several designs.

        Parameters
        ----------
        designs : iterable of sequences of float
            Designs; duplicates are fine.
        fingerprint : str
            Fingerprint the records must have been evaluated with.

        Returns
        -------
        dict
            Design key (:func:`design_key`) -> record, for the designs found.
        """
        return self.get_keys([design_key(d) for d in designs], fingerprint)

    def get_keys(self, keys: Iterable[str], fingerprint: str) -> dict[str, SampleRecord]:
        """The stored records of several design keys (:func:`design_key`): key -> record, for those found."""
        keys = list(dict.fromkeys(keys))
        found: dict[str, SampleRecord] = {}
        with self._sql("reading records") as conn:
            for start in range(0, len(keys), _CHUNK):
                chunk = keys[start : start + _CHUNK]
                marks = ",".join("?" * len(chunk))
                rows = conn.execute(
                    f"SELECT key, {_COLUMNS} FROM samples WHERE fingerprint = ? AND key IN ({marks})",
                    [fingerprint, *chunk],
                ).fetchall()
                for row in rows:
                    found[row[0]] = _row_to_record(row[1:])
        return found

    def missing(self, designs: Iterable[Sequence[float]], fingerprint: str) -> list[tuple[float, ...]]:
        """Designs not yet stored for this fingerprint, deduplicated by key, in first-seen order.

        Parameters
        ----------
        designs : iterable of sequences of float
            Designs.
        fingerprint : str
            Fingerprint of the run.

        Returns
        -------
        list of tuple
            The designs still to evaluate (failed and infeasible records count as stored).
        """
        unique: dict[str, tuple[float, ...]] = {}
        for d in designs:
            unique.setdefault(design_key(d), as_design(d))
        stored = self.get_keys(unique, fingerprint)
        return [d for k, d in unique.items() if k not in stored]

    def records(self, fingerprint: str | None = None, status: str | None = None) -> list[SampleRecord]:
        """All stored records, in insertion order.

        Parameters
        ----------
        fingerprint : str, optional
            Only the records of this fingerprint.
        status : str, optional
            Only the records with this status.

        Returns
        -------
        list of SampleRecord
        """
        where, args = _filter(fingerprint, status)
        with self._sql("reading records") as conn:
            rows = conn.execute(f"SELECT {_COLUMNS} FROM samples{where} ORDER BY id", args).fetchall()
            return [_row_to_record(r) for r in rows]

    def count(self, fingerprint: str | None = None, status: str | None = None) -> int:
        """Number of stored records.

        Parameters
        ----------
        fingerprint : str, optional
            Only the records of this fingerprint.
        status : str, optional
            Only the records with this status.

        Returns
        -------
        int
        """
        where, args = _filter(fingerprint, status)
        with self._sql("counting records") as conn:
            return conn.execute(f"SELECT COUNT(*) FROM samples{where}", args).fetchone()[0]

    def fingerprints(self) -> dict[str, int]:
        """Fingerprints present in the store with their number of records.

        Returns
        -------
        dict
            fingerprint -> number of records, in order of first appearance.
        """
        query = "SELECT fingerprint, COUNT(*) FROM samples GROUP BY fingerprint ORDER BY MIN(id)"
        with self._sql("reading fingerprints") as conn:
            return dict(conn.execute(query).fetchall())


def _unique(keys: Iterable[str]) -> Iterator[str]:
    """The keys without repeats, in order, read lazily."""
    seen: set[str] = set()
    for key in keys:
        if key not in seen:
            seen.add(key)
            yield key


def _code(exc: sqlite3.Error) -> int:
    """Primary SQLite result code of an error (0 if unknown)."""
    return (getattr(exc, "sqlite_errorcode", None) or 0) & 0xFF


def _why_read_only(path: Path) -> str:
    """Why ``path`` (or a file there) cannot be written: which of the file and its folder is read-only."""
    if path.exists():
        try:
            os.close(os.open(path, os.O_RDWR))
        except OSError:
            return "the file is read-only"
    try:
        # The WAL files (-wal, -shm) live beside the database: the folder must take new files.
        with tempfile.TemporaryFile(dir=path.parent):
            pass
    except OSError:
        return "its folder is read-only (SQLite needs to create files beside it)"
    return "it was opened read-only"


def _filter(fingerprint: str | None, status: str | None) -> tuple[str, list[str]]:
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


class _BadRow(ValueError):
    """A row SQLite reads fine but whose content is not a record (damaged JSON, a hand-edited value)."""


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
        raise _BadRow(f"{exc} in the row of design {design!r:.60}") from exc


class _Transaction:
    """``BEGIN IMMEDIATE`` … ``COMMIT`` (or ``ROLLBACK``) on an autocommit connection.

    IMMEDIATE takes the write lock up front, so a concurrent writer waits on the busy timeout at BEGIN instead of
    failing later with SQLITE_BUSY on a lock upgrade that the timeout cannot resolve.
    """

    def __init__(self, conn: sqlite3.Connection) -> None:
        self._conn = conn

    def __enter__(self) -> None:
        if self._conn.in_transaction:
            # A KeyboardInterrupt between an earlier BEGIN and its `with` block left a transaction open.
            self._conn.execute("ROLLBACK")
        self._conn.execute("BEGIN IMMEDIATE")

    def __exit__(self, exc_type: object, *rest: object) -> None:
        if not self._conn.in_transaction:
            return
        if exc_type is None:
            self._conn.execute("COMMIT")
        else:
            self._conn.execute("ROLLBACK")
