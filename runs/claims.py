"""Claims on designs: how concurrent runs on one store share the work instead of each evaluating everything.

A run claims the designs it is about to evaluate (table ``claims``), with a lease it renews while alive; another run
leaves validly claimed designs alone and waits for their results, and takes a claim over once its lease has expired
(or, on the same host, as soon as the claiming process is gone).

Each function runs its statements on the connection it is given, inside the caller's transaction; translating
SQLite errors is the caller's (:class:`~mechopt.runs.store_connection.StoreConnection`).
"""

from __future__ import annotations

import os
import socket
import sqlite3
import time
import uuid
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from itertools import islice

from mechopt.runs.sample_rows import MAX_KEYS_PER_QUERY, delete_failed_keys, stored_statuses

__all__ = [
    "Claim",
    "claim_keys",
    "drop_claims",
    "list_claims",
    "new_owner",
    "release_claims",
    "renew_claims",
    "unique_keys",
]


@dataclass(frozen=True)
class Claim:
    """A design a run is evaluating: other runs leave it alone until ``expires`` (s since the epoch, UTC)."""

    fingerprint: str
    key: str
    owner: str
    expires: float


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


def unique_keys(keys: Iterable[str]) -> Iterator[str]:
    """The keys without repeats, in order, read lazily."""
    seen: set[str] = set()
    for key in keys:
        if key not in seen:
            seen.add(key)
            yield key


class _Holders:
    """Which claim holders still count at one instant: a live owner's lease is honoured until it expires."""

    def __init__(self, owner: str, now: float) -> None:
        self.owner = owner
        self.now = now
        # Probing a process costs a system call: once per owner and claim call is enough.
        self._gone: dict[str, bool] = {}

    def blocks(self, who: str, expires: float) -> bool:
        """Whether a claim of ``who`` until ``expires`` (s since the epoch) keeps the design from ``owner``."""
        if who == self.owner or expires <= self.now:
            return False
        if who not in self._gone:
            self._gone[who] = _owner_is_gone(who)
        return not self._gone[who]


def _held(conn: sqlite3.Connection, fingerprint: str, keys: list[str]) -> dict[str, tuple[str, float]]:
    """Key -> (owner, expires) of the claims, valid or not, among at most MAX_KEYS_PER_QUERY keys."""
    marks = ",".join("?" * len(keys))
    return {
        key: (who, expires)
        for key, who, expires in conn.execute(
            f"SELECT key, owner, expires FROM claims WHERE fingerprint = ? AND key IN ({marks})",
            [fingerprint, *keys],
        )
    }


def claim_keys(
    conn: sqlite3.Connection,
    fingerprint: str,
    keys: Iterator[str],
    owner: str,
    lease_s: float,
    limit: int | None,
    redo_failed_before: str | None,
) -> list[str]:
    """Claim, inside the caller's write transaction, the keys neither stored nor validly claimed by another owner.

    Parameters
    ----------
    conn : sqlite3.Connection
        Connection in a ``BEGIN IMMEDIATE`` transaction (the check and the claim must be atomic).
    fingerprint : str
        Fingerprint of the run.
    keys : iterator of str
        Distinct design keys in order of preference, read only as far as needed to claim ``limit`` of them.
    owner : str
        This run's owner id (:func:`new_owner`); its own claims are renewed (and returned).
    lease_s : float
        Seconds the claims stay valid unless renewed, > 0.
    limit : int or None
        Claim at most this many (>= 1), or every claimable key.
    redo_failed_before : str or None
        ISO timestamp: a ``failed`` row written before it counts as not stored, and is deleted when its key is
        claimed.

    Returns
    -------
    list of str
        The keys now claimed by ``owner``, in the order of ``keys``.
    """
    # Without contention the first few keys are claimable: look at a few, then at more and more.
    size = MAX_KEYS_PER_QUERY if limit is None else min(MAX_KEYS_PER_QUERY, max(32, 2 * limit))
    taken: list[str] = []
    holders = _Holders(owner, time.time())
    while limit is None or len(taken) < limit:
        chunk = list(islice(keys, size))
        if not chunk:
            break
        size = min(2 * size, MAX_KEYS_PER_QUERY)
        stored = stored_statuses(conn, fingerprint, chunk)
        held = _held(conn, fingerprint, chunk)
        redo = []
        for key in chunk:
            if limit is not None and len(taken) >= limit:
                break
            if key in stored:
                status, stamp = stored[key]
                if not (redo_failed_before and status == "failed" and stamp < redo_failed_before):
                    continue
            if key in held and holders.blocks(*held[key]):
                continue
            taken.append(key)
            if key in stored:
                redo.append(key)
        delete_failed_keys(conn, fingerprint, redo)
    conn.executemany(
        "INSERT OR REPLACE INTO claims (fingerprint, key, owner, expires) VALUES (?, ?, ?, ?)",
        [(fingerprint, k, owner, holders.now + lease_s) for k in taken],
    )
    return taken


def renew_claims(conn: sqlite3.Connection, owner: str, lease_s: float) -> int:
    """Extend every claim of ``owner`` to ``lease_s`` seconds from now; number renewed."""
    return conn.execute("UPDATE claims SET expires = ? WHERE owner = ?", (time.time() + lease_s, owner)).rowcount


def release_claims(conn: sqlite3.Connection, owner: str, keys: Iterable[str] | None) -> int:
    """Drop the claims of ``owner``: all of them, or those of ``keys``; number dropped."""
    if keys is None:
        return conn.execute("DELETE FROM claims WHERE owner = ?", (owner,)).rowcount
    before = conn.total_changes
    conn.executemany("DELETE FROM claims WHERE owner = ? AND key = ?", [(owner, k) for k in keys])
    return conn.total_changes - before


def drop_claims(conn: sqlite3.Connection, designs: Iterable[tuple[str, str]]) -> None:
    """Drop any claim, whoever holds it, on (fingerprint, key) pairs whose result is now stored."""
    conn.executemany("DELETE FROM claims WHERE fingerprint = ? AND key = ?", designs)


def list_claims(conn: sqlite3.Connection, fingerprint: str | None) -> list[Claim]:
    """Current claims (valid or expired), oldest lease end first; only those of ``fingerprint`` when given."""
    where, args = ("WHERE fingerprint = ?", [fingerprint]) if fingerprint is not None else ("", [])
    rows = conn.execute(
        f"SELECT fingerprint, key, owner, expires FROM claims {where} ORDER BY expires, key", args
    ).fetchall()
    return [Claim(*row) for row in rows]
