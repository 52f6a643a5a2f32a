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

:class:`SampleStore` is the one interface; it composes the parts that live in their own modules: the record and its
key (``sample_record.py``), the file's layout (``store_schema.py``), the connection with its transactions and
one-line errors (``store_connection.py``), the queries of the ``samples`` table (``sample_rows.py``) and the claims
(``claims.py``).
"""

from __future__ import annotations

import sqlite3
from collections.abc import Iterable, Sequence
from pathlib import Path

from mechopt.errors import InputError
from mechopt.runs.claims import (
    Claim,
    claim_keys,
    drop_claims,
    list_claims,
    new_owner,
    release_claims,
    renew_claims,
    unique_keys,
)
from mechopt.runs.sample_record import KEY_DECIMALS, STATUSES, SampleRecord, as_design, design_key, utc_timestamp
from mechopt.runs.sample_rows import (
    count_rows,
    delete_failed,
    fingerprint_counts,
    insert_rows,
    record_row,
    select_keys,
    select_rows,
    status_filter,
)
from mechopt.runs.store_connection import StoreConnection
from mechopt.runs.store_schema import SCHEMA_VERSION

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
        self._db = StoreConnection(Path(path), float(timeout))
        # Fixed once the file is open.
        self.path, self.timeout = self._db.path, self._db.timeout
        #: Why the store cannot be written to (None if it can).
        self.read_only: str | None = self._db.read_only

    @property
    def _c(self) -> sqlite3.Connection:
        """The raw connection, for checks of the file's settings."""
        return self._db.conn

    def close(self) -> None:
        """Close the database connection (idempotent)."""
        self._db.close()

    def __enter__(self) -> SampleStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"SampleStore({str(self.path)!r}{', read-only' if self.read_only else ''})"

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
        rows = [record_row(r) for r in records]
        if not rows:
            return 0
        with self._db.write("storing results") as conn:
            inserted = insert_rows(conn, rows)
            drop_claims(conn, [r[:2] for r in rows])
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
        with self._db.write("deleting failed records") as conn:
            return delete_failed(conn, fingerprint)

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
        with self._db.write("claiming designs") as conn:
            return claim_keys(conn, fingerprint, unique_keys(keys), owner, lease_s, limit, redo_failed_before)

    def renew_claims(self, owner: str, lease_s: float) -> int:
        """Extend every claim of ``owner`` to ``lease_s`` seconds from now (the heartbeat of a live run).

        Returns
        -------
        int
            Number of claims renewed.
        """
        with self._db.write("renewing claims") as conn:
            return renew_claims(conn, owner, lease_s)

    def release_claims(self, owner: str, keys: Iterable[str] | None = None) -> int:
        """Drop claims of ``owner``: all of them, or those of ``keys``.

        Returns
        -------
        int
            Number of claims dropped.
        """
        with self._db.write("releasing claims") as conn:
            return release_claims(conn, owner, keys)

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
        with self._db.sql("reading claims") as conn:
            return list_claims(conn, fingerprint)

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
        distinct = list(dict.fromkeys(keys))
        with self._db.sql("reading records") as conn:
            return select_keys(conn, distinct, fingerprint)

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
        where, args = status_filter(fingerprint, status)
        with self._db.sql("reading records") as conn:
            return select_rows(conn, where, args)

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
        where, args = status_filter(fingerprint, status)
        with self._db.sql("counting records") as conn:
            return count_rows(conn, where, args)

    def fingerprints(self) -> dict[str, int]:
        """Fingerprints present in the store with their number of records.

        Returns
        -------
        dict
            fingerprint -> number of records, in order of first appearance.
        """
        with self._db.sql("reading fingerprints") as conn:
            return fingerprint_counts(conn)
