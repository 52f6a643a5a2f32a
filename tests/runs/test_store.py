"""SampleStore on real SQLite files: round trip, duplicates, fingerprints, float noise, damaged, old and read-only
files, concurrency."""

from __future__ import annotations

import contextlib
import json
import math
import os
import sqlite3
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from mechopt.errors import InputError
from mechopt.runs.executors import InProcessExecutor
from mechopt.runs.fingerprint import fingerprint
from mechopt.runs.sampling import sample_designs
from mechopt.runs.store import SCHEMA_VERSION, SampleRecord, SampleStore, design_key

HERE = Path(__file__).resolve().parents[1] / "helpers"  # toy_eval, for the child processes too
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
import toy_eval  # noqa: E402
from toy_eval import ToyProblem  # noqa: E402

H1 = fingerprint({"problem": "toy", "engine": "analytic"})
H2 = fingerprint({"problem": "toy", "engine": "pymunk"})


def _ok(design, h=H1, f=1.25, **kw) -> SampleRecord:
    return SampleRecord(design=design, fingerprint=h, status="ok", outputs={"f": f, "g": 2 * f}, **kw)


def test_round_trip_keeps_every_field_for_any_dimension(tmp_path):
    rec = SampleRecord(design=(25.5, 80.125, 60.0, 0.5), fingerprint=H1, status="ok", wall_time_s=0.042,
                       outputs={"f": 1.5, "g": -2.0, "n_steps": 200, "peak": [1.5, -2.0], "engine": "pymunk"})
    one = _ok((3.0,))
    bad = SampleRecord(design=(1.0, 9.0), fingerprint=H1, status="infeasible", error="cannot assemble")
    with SampleStore(tmp_path / "sub" / "s.sqlite") as store:  # parent folders are created
        assert store.put(rec) and store.put(one) and store.put(bad)
    with SampleStore(tmp_path / "sub" / "s.sqlite") as store:  # and it persists across connections
        assert store.get(rec.design, H1) == rec  # exact: designs and outputs are JSON of IEEE doubles
        assert store.get([3.0], H1) == one
        assert store.get(np.array([1.0, 9.0]), H1) == bad
        assert [r.key for r in store.records(H1)] == [rec.key, one.key, bad.key]  # insertion order
        assert store.count() == 3 and store.count(H1, status="infeasible") == 1
        assert store.records(H1, status="ok") == [rec, one]
        assert store.fingerprints() == {H1: 3}
    d = json.loads(json.dumps(rec.to_dict()))
    assert d["design"] == [25.5, 80.125, 60.0, 0.5] and d["key"] == rec.key and d["outputs"]["peak"] == [1.5, -2.0]
    assert SampleRecord(**{k: v for k, v in d.items() if k != "key"}) == rec


def test_value_is_nan_unless_ok_and_numeric():
    rec = SampleRecord(design=(1.0, 2.0), fingerprint=H1, status="ok", outputs={"f": 2, "label": "x", "flag": True})
    assert rec.value("f") == 2.0 and isinstance(rec.value("f"), float)
    assert math.isnan(rec.value("missing")) and math.isnan(rec.value("label")) and math.isnan(rec.value("flag"))
    failed = SampleRecord(design=(1.0, 2.0), fingerprint=H1, status="failed", error="RuntimeError: boom")
    assert math.isnan(failed.value("f")) and not failed.ok


def test_duplicate_is_ignored_and_first_row_kept(tmp_path):
    with SampleStore(tmp_path / "s.sqlite") as store:
        first, second = _ok((10, 20, 30), f=1.0), _ok((10, 20, 30), f=99.0)
        assert store.put(first) is True
        assert store.put(second) is False
        assert store.put_many([second, _ok((10, 20, 31))]) == 1
        assert store.count(H1) == 2
        assert store.get((10, 20, 30), H1).value("f") == 1.0


def test_fingerprint_isolates_runs(tmp_path):
    d = (12.0, 70.0)
    with SampleStore(tmp_path / "s.sqlite") as store:
        assert store.put(_ok(d, H1, f=1.0)) and store.put(_ok(d, H2, f=2.0))
        assert store.count() == 2 and store.fingerprints() == {H1: 1, H2: 1}
        assert store.get(d, H1).value("f") == 1.0 and store.get(d, H2).value("f") == 2.0
        assert store.missing([d, (1.0, 2.0)], H1) == [(1.0, 2.0)]
        assert store.get((1.0, 2.0), H2) is None
        assert list(store.get_many([d], fingerprint({"other": 1}))) == []


def test_float_noise_maps_to_one_key(tmp_path):
    noisy = (0.1 + 0.2, 100.0 * (1 + 1e-15), 40.000000000001)
    clean = (0.3, 100.0, 40.0)
    assert design_key(noisy) == design_key(clean) == "0.300000000,100.000000000,40.000000000"
    assert design_key((-0.0, 1, 2)) == design_key((0.0, 1.0, 2.0))
    assert design_key(np.array([0.3, 100.0, 40.0])) == design_key(clean)
    assert design_key((0.3, 100.0, 40.000001)) != design_key(clean)  # 1e-6 is a different design
    assert design_key([2.5]) == "2.500000000" and design_key((1, 2, 3, 4)).count(",") == 3
    with SampleStore(tmp_path / "s.sqlite") as store:
        assert store.put(_ok(clean))
        assert not store.put(_ok(noisy))
        assert store.missing([noisy, clean, noisy], H1) == []
        assert set(store.get_many([noisy], H1)) == {design_key(clean)}
        new = (0.3, 100.0, 40.001)
        assert store.missing([new, (0.3, 100.0, 40.001 + 1e-13)], H1) == [new]


def test_forget_failed_deletes_only_failures_of_one_fingerprint(tmp_path):
    with SampleStore(tmp_path / "s.sqlite") as store:
        store.put_many([
            _ok((1.0, 1.0)),
            SampleRecord(design=(2.0, 1.0), fingerprint=H1, status="failed", error="RuntimeError: x"),
            SampleRecord(design=(3.0, 1.0), fingerprint=H1, status="infeasible", error="no"),
            SampleRecord(design=(2.0, 1.0), fingerprint=H2, status="failed", error="RuntimeError: x"),
        ])
        assert store.forget_failed(H1) == 1
        assert store.forget_failed(H1) == 0
        assert [r.status for r in store.records(H1)] == ["ok", "infeasible"]
        assert store.count(H2, status="failed") == 1


def test_invalid_inputs_are_one_line_errors(tmp_path):
    with pytest.raises(InputError, match="at least one value"):
        design_key(())
    with pytest.raises(InputError, match="finite"):
        design_key((1.0, float("inf"), 2.0))
    with pytest.raises(InputError, match="sequence of numbers"):
        design_key(("a", 1.0))
    with pytest.raises(InputError, match="status"):
        SampleRecord(design=(1, 2), fingerprint=H1, status="maybe")
    with pytest.raises(InputError, match="has no outputs"):
        SampleRecord(design=(1, 2), fingerprint=H1, status="failed", outputs={"f": 1.0})
    with SampleStore(tmp_path / "s.sqlite") as store, pytest.raises(InputError, match="not JSON-serializable"):
        store.put(SampleRecord(design=(1, 2), fingerprint=H1, status="ok", outputs={"f": object()}))
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"this is not a database, just some text long enough to have a header" * 20)
    with pytest.raises(InputError, match="not a usable sample store") as info:
        SampleStore(junk)
    assert "\n" not in str(info.value)
    store = SampleStore(tmp_path / "s.sqlite")
    store.close()
    store.close()  # idempotent
    with pytest.raises(InputError, match="closed"):
        store.count()


def test_old_newer_and_foreign_files_are_one_line_errors(tmp_path):
    old = tmp_path / "old.sqlite"
    with contextlib.closing(sqlite3.connect(old)) as conn:  # mechopt 0.1's layout, with one row
        conn.execute("CREATE TABLE samples (id INTEGER PRIMARY KEY, settings_hash TEXT, key TEXT, oa REAL, ab REAL,"
                     " bc REAL, status TEXT, t_rms REAL, t_max REAL, extra TEXT, error TEXT, wall_time_s REAL,"
                     " timestamp TEXT, UNIQUE (settings_hash, key))")
        conn.execute("INSERT INTO samples VALUES (1, 'h', 'k', 1, 2, 3, 'ok', 1.0, 2.0, '{}', NULL, 0.1, 't')")
        conn.execute("PRAGMA user_version = 1")
        conn.commit()
    version_only = tmp_path / "v1.sqlite"
    with contextlib.closing(sqlite3.connect(version_only)) as conn:
        conn.execute("PRAGMA user_version = 1")
    for path in (old, version_only):
        with pytest.raises(InputError) as info:
            SampleStore(path)
        message = str(info.value)
        assert "\n" not in message and str(path) in message
        assert "mechopt 0.1 (fixed four-bar columns)" in message and "move it away or delete it" in message
    with contextlib.closing(sqlite3.connect(old)) as conn:  # untouched
        assert conn.execute("SELECT COUNT(*) FROM samples").fetchone()[0] == 1

    newer = tmp_path / "newer.sqlite"
    SampleStore(newer).close()
    with contextlib.closing(sqlite3.connect(newer)) as conn:
        conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
    with pytest.raises(InputError, match="newer mechopt"):
        SampleStore(newer)

    foreign = tmp_path / "foreign.sqlite"
    with contextlib.closing(sqlite3.connect(foreign)) as conn:
        conn.execute("CREATE TABLE trials (id INTEGER)")
    with pytest.raises(InputError, match="not a mechopt sample store .*trials"):
        SampleStore(foreign)


def test_garbage_in_the_middle_of_the_file_is_a_one_line_error(tmp_path):
    """A file whose header is fine but whose table pages were overwritten: the damage shows on reading, mid-run."""
    path = tmp_path / "s.sqlite"
    rng = np.random.default_rng(11)
    with SampleStore(path) as store:
        store.put_many(_ok((float(i), 1.0), f=float(i)) for i in range(3000))
    size = path.stat().st_size
    assert not Path(f"{path}-wal").exists()  # the last close checkpointed everything into the file
    with open(path, "r+b") as fh:  # two fifths of the pages, from the middle on, become noise
        fh.seek(size * 2 // 5)
        fh.write(rng.integers(0, 256, size // 5, dtype=np.uint8).tobytes())
    with SampleStore(path) as store:  # page 1 (header, schema) is intact: opening works
        with pytest.raises(InputError) as info:
            store.records(H1)
        message = str(info.value)
        assert "\n" not in message and "not a usable sample store" in message and "reading records" in message
        with pytest.raises(InputError, match="not a usable sample store"):
            store.get_many([(float(i), 1.0) for i in range(3000)], H1)


def _writable(path: Path) -> bool:
    try:
        if path.is_dir():
            with tempfile.TemporaryFile(dir=path):
                return True
        os.close(os.open(path, os.O_RDWR))
        return True
    except OSError:
        return False


@contextlib.contextmanager
def _read_only(path: Path):
    """Make a file or folder read-only: clear its write bits, and for root (who ignores them) set it immutable."""
    mode = path.stat().st_mode
    path.chmod(mode & ~0o222)
    immutable = False
    try:
        if _writable(path):
            if subprocess.run(["chattr", "+i", str(path)], capture_output=True).returncode != 0:
                pytest.skip("cannot make a path read-only here (root without chattr)")
            immutable = True
            assert not _writable(path)
        yield
    finally:
        if immutable:
            subprocess.run(["chattr", "-i", str(path)], check=True)
        path.chmod(mode)


@pytest.mark.parametrize("what", ["file", "folder"])
def test_read_only_store_reads_and_refuses_writes_in_one_line(tmp_path, what):
    folder = tmp_path / "ro"
    path = folder / "s.sqlite"
    designs = toy_eval.random_designs(4, seed=12)
    with SampleStore(path) as store:
        store.put_many([_ok((1.0, 2.0)), _ok((3.0, 4.0), f=5.0)])
        done = sample_designs(designs, ToyProblem(), store, executor=InProcessExecutor(), progress=False)
    with _read_only(path if what == "file" else folder):
        with SampleStore(path) as store:
            assert store.count(H1) == 2 and store.get((3.0, 4.0), H1).value("f") == 5.0
            assert store.missing([(1.0, 2.0), (9.0, 9.0)], H1) == [(9.0, 9.0)]
            # A finished run is served from a read-only store: nothing to write.
            again = sample_designs(designs, ToyProblem(), store, executor=InProcessExecutor(), progress=False)
            assert again.records == done.records and again.n_cached == 4
            for write in (lambda: store.put(_ok((9.0, 9.0))), lambda: store.forget_failed(H1),
                          lambda: store.claim(H1, ["k"], "me", 10.0),
                          lambda: sample_designs([*designs, (20.0, 70.0, 60.0)], ToyProblem(), store,
                                                 executor=InProcessExecutor(), progress=False)):
                with pytest.raises(InputError) as info:
                    write()
                message = str(info.value)
                assert "\n" not in message and "not a usable" not in message
                assert f"cannot write to the sample store {path}: " in message
                assert ("the file is read-only" if what == "file" else "its folder is read-only") in message
        if what == "folder":
            with pytest.raises(InputError, match="cannot create the sample store .*its folder is read-only"):
                SampleStore(folder / "new.sqlite")


def test_wal_mode_and_concurrent_reader(tmp_path):
    path = tmp_path / "s.sqlite"
    with SampleStore(path) as writer, SampleStore(path) as reader:
        assert writer._c.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        writer.put(_ok((1, 2, 3)))
        assert reader.count(H1) == 1  # committed at once, visible to another connection
        # An open read transaction elsewhere does not block the writer (WAL).
        raw = sqlite3.connect(path)
        raw.execute("BEGIN")
        raw.execute("SELECT COUNT(*) FROM samples").fetchone()
        assert writer.put(_ok((1, 2, 4)))
        raw.rollback()
        raw.close()
        assert reader.count(H1) == 2


def test_lock_held_too_long_is_a_one_line_error(tmp_path):
    path = tmp_path / "s.sqlite"
    SampleStore(path).close()
    with contextlib.closing(sqlite3.connect(path, isolation_level=None)) as raw, \
            SampleStore(path, timeout=0.2) as store:
        raw.execute("BEGIN IMMEDIATE")  # another process holds the write lock
        with pytest.raises(InputError, match=r"locked by another process \(waited 0.2 s while storing results\)"):
            store.put(_ok((1.0, 2.0)))
        raw.execute("ROLLBACK")
        assert store.put(_ok((1.0, 2.0)))  # the connection is usable afterwards


def test_processes_open_new_stores_together_and_write_overlapping_designs(tmp_path):
    """Four processes open the same *new* file at the same instant (the first run of parallel workers): switching a
    fresh database to WAL can report 'database is locked' without waiting; the store retries instead of failing.
    Three new files in turn, each opened by all four at one instant.  Then the four write 1000 designs each into one
    file, overlapping by half: no 'database is locked', every design exactly once."""
    script = tmp_path / "opener.py"
    script.write_text(
        textwrap.dedent(
            f"""
            import sys, time
            from mechopt.runs.store import SampleRecord, SampleStore

            def wait_for_start():
                start = float(sys.stdin.readline())
                while time.time() < start:
                    pass

            print("ready", flush=True)
            for path in sys.argv[3:]:
                wait_for_start()
                with SampleStore(path) as store:
                    print(store.count({H1!r}), flush=True)
            lo = int(sys.argv[2])
            wait_for_start()
            inserted = 0
            with SampleStore(sys.argv[1]) as store:
                for i in range(lo, lo + 1000):
                    rec = SampleRecord(design=(float(i), 1.0), fingerprint={H1!r}, status="ok", outputs={{"f": i}})
                    inserted += store.put(rec)
            print(inserted, flush=True)
            """
        )
    )
    paths = [str(tmp_path / f"new{trial}.sqlite") for trial in range(3)]
    shared = tmp_path / "shared.sqlite"

    def go(procs: list[subprocess.Popen]) -> list[str]:
        start = time.time() + 0.2
        for p in procs:
            p.stdin.write(f"{start}\n")
            p.stdin.flush()
        return [p.stdout.readline().strip() for p in procs]

    procs = [subprocess.Popen([sys.executable, str(script), str(shared), str(500 * i), *paths], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for i in range(4)]
    try:
        for p in procs:  # every interpreter has done its imports
            assert p.stdout.readline().strip() == "ready", p.communicate(timeout=60)
        for _ in paths:
            assert go(procs) == ["0"] * 4, [p.poll() for p in procs]
        inserted = go(procs)
        results = [p.communicate(timeout=60) for p in procs]
        assert [p.returncode for p in procs] == [0] * 4, [err for _, err in results if err]
    finally:
        for p in procs:
            p.kill()
            p.wait()
    assert sum(int(n) for n in inserted) == 2500
    with SampleStore(shared) as store:
        assert store.count(H1) == 2500
        assert sorted(r.design[0] for r in store.records(H1)) == [float(i) for i in range(2500)]
