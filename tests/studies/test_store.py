"""SampleStore on real SQLite files: round trip, duplicates, settings isolation, float noise, concurrency."""

from __future__ import annotations

import json
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from mechopt.errors import InputError
from mechopt.studies.store import SampleRecord, SampleStore, design_key, settings_hash

REPO = Path(__file__).resolve().parents[2]
H1 = settings_hash({"engine": "analytic", "rpm": 20})
H2 = settings_hash({"engine": "pymunk", "rpm": 20})


def _ok(design, h=H1, t_rms=1.25, **kw) -> SampleRecord:
    oa, ab, bc = design
    return SampleRecord(oa=oa, ab=ab, bc=bc, settings_hash=h, status="ok", t_rms=t_rms, t_max=2 * t_rms, **kw)


def test_round_trip_keeps_every_field(tmp_path):
    rec = _ok((25.5, 80.125, 60.0), extra={"n_steps": 200, "peak": [1.5, -2.0]}, wall_time_s=0.042)
    bad = SampleRecord(oa=1.0, ab=9.0, bc=1.0, settings_hash=H1, status="infeasible", error="cannot assemble")
    with SampleStore(tmp_path / "sub" / "s.sqlite") as store:  # parent folders are created
        assert store.put(rec) and store.put(bad)
    with SampleStore(tmp_path / "sub" / "s.sqlite") as store:  # and it persists across connections
        got = store.get(rec.design, H1)
        assert got == rec  # exact: REAL columns store IEEE doubles, extra is JSON
        assert store.get(bad.design, H1) == bad
        assert [r.key for r in store.records(H1)] == [rec.key, bad.key]  # insertion order
        assert store.count() == 2 and store.count(H1, status="infeasible") == 1
        assert store.records(H1, status="ok") == [rec]
        assert store.settings_hashes() == {H1: 2}
    assert json.loads(json.dumps(rec.to_dict()))["key"] == rec.key


def test_duplicate_is_ignored_and_first_row_kept(tmp_path):
    with SampleStore(tmp_path / "s.sqlite") as store:
        first, second = _ok((10, 20, 30), t_rms=1.0), _ok((10, 20, 30), t_rms=99.0)
        assert store.put(first) is True
        assert store.put(second) is False
        assert store.put_many([second, _ok((10, 20, 31))]) == 1
        assert store.count(H1) == 2
        assert store.get((10, 20, 30), H1).t_rms == 1.0


def test_settings_hash_isolates_runs(tmp_path):
    d = (12.0, 70.0, 50.0)
    with SampleStore(tmp_path / "s.sqlite") as store:
        assert store.put(_ok(d, H1, t_rms=1.0)) and store.put(_ok(d, H2, t_rms=2.0))
        assert store.count() == 2
        assert store.get(d, H1).t_rms == 1.0 and store.get(d, H2).t_rms == 2.0
        assert store.missing([d, (1.0, 2.0, 3.0)], H1) == [(1.0, 2.0, 3.0)]
        assert store.get((1.0, 2.0, 3.0), H2) is None
        assert list(store.get_many([d], settings_hash({"other": 1}))) == []


def test_float_noise_maps_to_one_key(tmp_path):
    noisy = (0.1 + 0.2, 100.0 * (1 + 1e-15), 40.000000000001)
    clean = (0.3, 100.0, 40.0)
    assert design_key(noisy) == design_key(clean) == "0.300000000,100.000000000,40.000000000"
    assert design_key((-0.0, 1, 2)) == design_key((0.0, 1.0, 2.0))
    assert design_key(np.array([0.3, 100.0, 40.0])) == design_key(clean)
    assert design_key((0.3, 100.0, 40.000001)) != design_key(clean)  # 1e-6 mm is a different design
    with SampleStore(tmp_path / "s.sqlite") as store:
        assert store.put(_ok(clean))
        assert not store.put(_ok(noisy))
        assert store.missing([noisy, clean, noisy], H1) == []
        assert set(store.get_many([noisy], H1)) == {design_key(clean)}
        new = (0.3, 100.0, 40.001)
        assert store.missing([new, (0.3, 100.0, 40.001 + 1e-13)], H1) == [new]


def test_settings_hash_is_canonical():
    a = {"rpm": 20, "engine": {"name": "pymunk", "dt": 0.001}, "box": (10, 50)}
    b = {"engine": {"dt": 1e-3, "name": "pymunk"}, "box": [10.0, 50.0], "rpm": 20.0}
    assert settings_hash(a) == settings_hash(b)
    assert len(settings_hash(a)) == 64
    assert settings_hash(a) != settings_hash({**a, "rpm": 21})
    assert settings_hash({"x": np.float64(0.5), "n": np.int64(3)}) == settings_hash({"x": 0.5, "n": 3})
    assert settings_hash({"flag": True}) != settings_hash({"flag": 1})
    with pytest.raises(InputError, match="finite"):
        settings_hash({"dt": float("nan")})
    with pytest.raises(InputError, match="JSON-like"):
        settings_hash({"f": object()})


def test_invalid_inputs_are_one_line_errors(tmp_path):
    with pytest.raises(InputError, match="three lengths"):
        design_key((1.0, 2.0))
    with pytest.raises(InputError, match="finite"):
        design_key((1.0, float("inf"), 2.0))
    with pytest.raises(InputError, match="status"):
        SampleRecord(oa=1, ab=2, bc=3, settings_hash=H1, status="maybe")
    with pytest.raises(InputError, match="finite t_rms"):
        SampleRecord(oa=1, ab=2, bc=3, settings_hash=H1, status="ok", t_rms=float("nan"), t_max=1.0)
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"this is not a database, just some text long enough to have a header" * 20)
    with pytest.raises(InputError, match="not a usable sample store"):
        SampleStore(junk)
    store = SampleStore(tmp_path / "s.sqlite")
    store.close()
    store.close()  # idempotent
    with pytest.raises(InputError, match="closed"):
        store.count()


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


def test_two_processes_write_the_same_file(tmp_path):
    """Two writer processes with overlapping designs: no 'database is locked', every key exactly once."""
    path = tmp_path / "s.sqlite"
    script = tmp_path / "writer.py"
    script.write_text(
        textwrap.dedent(
            f"""
            import sys
            sys.path.insert(0, {str(REPO)!r})
            from mechopt.studies.store import SampleRecord, SampleStore
            lo, hi = int(sys.argv[1]), int(sys.argv[2])
            inserted = 0
            with SampleStore({str(path)!r}) as store:
                for i in range(lo, hi):
                    rec = SampleRecord(oa=float(i), ab=1.0, bc=2.0, settings_hash={H1!r}, status="ok",
                                       t_rms=float(i), t_max=float(i))
                    inserted += store.put(rec)
            print(inserted)
            """
        )
    )
    procs = [
        subprocess.Popen([sys.executable, str(script), lo, hi], stdout=subprocess.PIPE, text=True)
        for lo, hi in (("0", "2000"), ("1000", "3000"))
    ]
    outs = [p.communicate(timeout=60)[0] for p in procs]
    assert [p.returncode for p in procs] == [0, 0]
    assert sum(int(o) for o in outs) == 3000
    with SampleStore(path) as store:
        assert store.count(H1) == 3000
        assert sorted(r.oa for r in store.records(H1)) == [float(i) for i in range(3000)]


def test_processes_opening_a_new_store_together_all_succeed(tmp_path):
    """Six processes open the same *new* file at the same instant (the first run of parallel workers): switching a
    fresh database to WAL can report 'database is locked' without waiting; the store retries instead of failing."""
    script = tmp_path / "opener.py"
    script.write_text(
        textwrap.dedent(
            f"""
            import sys, time
            sys.path.insert(0, {str(REPO)!r})
            from mechopt.studies.store import SampleStore
            start = float(sys.argv[2])
            while time.time() < start:
                pass
            with SampleStore(sys.argv[1]) as store:
                print(store.count({H1!r}))
            """
        )
    )
    for trial in range(5):
        path = tmp_path / f"new{trial}.sqlite"
        start = time.time() + 1.5  # after every interpreter has started
        procs = [subprocess.Popen([sys.executable, str(script), str(path), str(start)], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True) for _ in range(6)]
        results = [p.communicate(timeout=60) for p in procs]
        assert [p.returncode for p in procs] == [0] * 6, [err for _, err in results if err]
        assert [out.strip() for out, _ in results] == ["0"] * 6
