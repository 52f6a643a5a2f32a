"""The sample store's SQLite connection: opening (read-write, else read-only), transactions, one-line errors.

The file is in WAL mode with a busy timeout, so other processes read it (or write to it) while a run is going on.  A
file (or folder) that is not writable is opened read-only: reading works and writing raises a one-line
:class:`~mechopt.errors.InputError`, as does every SQLite error met while using the connection.
"""

from __future__ import annotations

import os
import sqlite3
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from urllib.parse import quote

from mechopt.errors import InputError
from mechopt.runs.sample_rows import UnreadableRow
from mechopt.runs.store_schema import create_schema, holds_current_schema

__all__ = ["StoreConnection", "Transaction"]

# Primary SQLite result codes (sqlite3.Error.sqlite_errorcode & 0xFF).
_BUSY, _LOCKED, _READONLY, _IOERR, _CORRUPT, _FULL, _CANTOPEN, _NOTADB = 5, 6, 8, 10, 11, 13, 14, 26


def _code(exc: sqlite3.Error) -> int:
    """Primary SQLite result code of an error (0 if unknown)."""
    return (getattr(exc, "sqlite_errorcode", None) or 0) & 0xFF


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


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


class Transaction:
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


class StoreConnection:
    """Autocommit connection to a sample store file, created with the current schema if missing.

    Parameters
    ----------
    path : Path
        The database file; created with its parent folders if missing.
    timeout : float
        Seconds to wait for a lock held by another process before giving up.

    Raises
    ------
    InputError
        If the file is not a SQLite database, is corrupt, was written by another version of mechopt, or cannot be
        created.
    """

    def __init__(self, path: Path, timeout: float) -> None:
        self.path = path
        self.timeout = timeout
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
                raise self.error(exc, "opening it") from exc
        except BaseException:
            self.close()
            raise

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
                # One transaction for the check and the creation: outside it, the version and the table list are two
                # reads, and another process's creation can land between them (version 0 with every table).
                with self.transaction():
                    if holds_current_schema(self.conn, self.path):
                        return
                    create_schema(conn)
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
                if not holds_current_schema(self.conn, self.path):
                    raise InputError(f"the sample store {self.path} is empty and {self.read_only}")
                return
            except sqlite3.DatabaseError as exc:
                self.close()
                if _code(exc) == _CANTOPEN and suffix != "?immutable=1":
                    continue
                raise self.error(exc, "opening it read-only") from exc
            except BaseException:
                self.close()
                raise

    @property
    def conn(self) -> sqlite3.Connection:
        """The open connection; InputError once closed."""
        if self._conn is None:
            raise InputError(f"the sample store {self.path} is closed")
        return self._conn

    def transaction(self) -> Transaction:
        """A write transaction on the connection, for a ``with`` block."""
        return Transaction(self.conn)

    def error(self, exc: sqlite3.DatabaseError, doing: str) -> InputError:
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
    def sql(self, doing: str, write: bool = False) -> Iterator[sqlite3.Connection]:
        """The connection, with every SQLite error (a corrupt page met mid-file included) turned into one line."""
        if write and self.read_only:
            raise InputError(f"cannot write to the sample store {self.path}: {self.read_only}")
        conn = self.conn
        try:
            yield conn
        except sqlite3.DatabaseError as exc:
            raise self.error(exc, doing) from exc
        except UnreadableRow as exc:
            raise InputError(
                f"{self.path} is not a usable sample store (unreadable row: {_one_line(str(exc))}); move it away "
                "or delete it, its samples will be simulated again"
            ) from exc

    @contextmanager
    def write(self, doing: str) -> Iterator[sqlite3.Connection]:
        """:meth:`sql` for writing, inside one committed transaction (rolled back if the block raises)."""
        with self.sql(doing, write=True) as conn, self.transaction():
            yield conn

    def close(self) -> None:
        """Close the connection (idempotent)."""
        if self._conn is not None:
            self._conn.close()
            self._conn = None
