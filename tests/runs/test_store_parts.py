"""The parts SampleStore composes, on their own: schema check, samples rows, claims, connection; and the order of
checks the store keeps when it delegates to them."""

from __future__ import annotations

import contextlib
import sqlite3
from pathlib import Path

import pytest

from mechopt.errors import InputError
from mechopt.runs.claims import claim_keys, list_claims, new_owner, unique_keys
from mechopt.runs.cooperative_evaluation import is_final
from mechopt.runs.sample_record import SampleRecord
from mechopt.runs.sample_rows import (
    UnreadableRow,
    insert_rows,
    record_row,
    select_keys,
    select_rows,
    status_filter,
)
from mechopt.runs.store import SampleStore
from mechopt.runs.store_connection import StoreConnection
from mechopt.runs.store_schema import SCHEMA_VERSION, create_schema, holds_current_schema

H = "fp-parts"


def _ok(x: float, **kw) -> SampleRecord:
    return SampleRecord(design=(x, 1.0), fingerprint=H, status="ok", outputs={"f": x}, **kw)


@contextlib.contextmanager
def _schema_db(path: Path):
    with contextlib.closing(sqlite3.connect(path, isolation_level=None)) as conn:
        create_schema(conn)
        yield conn


def test_schema_check_tells_empty_current_and_foreign_files(tmp_path):
    with contextlib.closing(sqlite3.connect(tmp_path / "empty.sqlite")) as conn:
        assert holds_current_schema(conn, tmp_path / "empty.sqlite") is False
    with _schema_db(tmp_path / "new.sqlite") as conn:
        assert holds_current_schema(conn, tmp_path / "new.sqlite") is True
        assert conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION
    with contextlib.closing(sqlite3.connect(tmp_path / "other.sqlite")) as conn:
        conn.execute("CREATE TABLE results (x REAL)")
        with pytest.raises(InputError, match=r"not a mechopt sample store \(it holds the tables results\)"):
            holds_current_schema(conn, tmp_path / "other.sqlite")


def test_rows_round_trip_and_keep_the_first_row_of_a_design(tmp_path):
    first, again = _ok(2.0), SampleRecord(design=(2.0, 1.0), fingerprint=H, status="failed", error="boom")
    with _schema_db(tmp_path / "s.sqlite") as conn:
        assert insert_rows(conn, [record_row(first), record_row(_ok(3.0))]) == 2
        assert insert_rows(conn, [record_row(again)]) == 0
        found = select_keys(conn, [first.key, "9.000000000,9.000000000"], H)
        assert found == {first.key: first}
        where, args = status_filter(H, "ok")
        assert [r.design for r in select_rows(conn, where, args)] == [(2.0, 1.0), (3.0, 1.0)]
        conn.execute("UPDATE samples SET outputs = '{not json' WHERE key = ?", (first.key,))
        with pytest.raises(UnreadableRow, match="in the row of design"):
            select_rows(conn, where, args)


def test_record_row_refuses_outputs_json_cannot_hold():
    record = SampleRecord(design=(1.0,), fingerprint=H, status="ok", outputs={"f": object()})
    with pytest.raises(InputError, match="not JSON-serializable"):
        record_row(record)


def test_claim_keys_reads_only_as_many_keys_as_it_needs(tmp_path):
    read = []

    def keys():
        for i in range(10_000):
            read.append(i)
            yield f"k{i}"

    with _schema_db(tmp_path / "s.sqlite") as conn:
        owner = new_owner()
        assert claim_keys(conn, H, keys(), owner, 60.0, 3, None) == ["k0", "k1", "k2"]
        assert len(read) == 32  # one first look of max(32, 2 * limit) keys, not all 10 000
        assert [c.key for c in list_claims(conn, H)] == ["k0", "k1", "k2"]
        # Another live owner leaves them alone; the same owner renews them.
        assert claim_keys(conn, H, iter(["k0", "k1", "k5"]), new_owner(), 60.0, None, None) == ["k5"]
        assert claim_keys(conn, H, iter(["k0"]), owner, 60.0, None, None) == ["k0"]


def test_unique_keys_is_lazy_and_keeps_first_order():
    seen = unique_keys(iter(["b", "a", "b", "c", "a"]))
    assert next(seen) == "b"
    assert list(seen) == ["a", "c"]


def test_is_final_redoes_only_failures_older_than_the_cut_off():
    old_failure = SampleRecord(design=(1.0,), fingerprint=H, status="failed", timestamp="2026-01-01T00:00:00.000Z")
    assert is_final(old_failure, None)
    assert not is_final(old_failure, "2026-01-01T00:00:00.001Z")
    assert is_final(old_failure, "2026-01-01T00:00:00.000Z")
    assert is_final(_ok(1.0, timestamp="2026-01-01T00:00:00.000Z"), "2026-02-01T00:00:00.000Z")


def test_connection_write_rolls_back_a_failed_block(tmp_path):
    db = StoreConnection(tmp_path / "s.sqlite", 5.0)
    try:
        with pytest.raises(RuntimeError), db.write("testing") as conn:
            insert_rows(conn, [record_row(_ok(1.0))])
            raise RuntimeError
        with db.sql("counting") as conn:
            assert conn.execute("SELECT COUNT(*) FROM samples").fetchone()[0] == 0
    finally:
        db.close()
    with pytest.raises(InputError, match="is closed"):
        db.transaction()


def test_store_checks_its_arguments_before_touching_the_file(tmp_path):
    store = SampleStore(tmp_path / "s.sqlite")
    store.close()
    with pytest.raises(InputError, match="status must be one of"):
        store.records(status="done")
    with pytest.raises(InputError, match="lease_s must be a positive number"):
        store.claim(H, ["k"], new_owner(), 0.0)
    with pytest.raises(InputError, match="is closed"):
        store.records()
