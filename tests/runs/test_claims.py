"""Claims: concurrent runs on one store share the work; the claims of a dead run are taken over."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import threading
import time
from collections import Counter
from pathlib import Path

from mechopt.runs.executors import InProcessExecutor
from mechopt.runs.sampling import sample_designs
from mechopt.runs.store import SampleRecord, SampleStore, design_key, new_owner

HERE = Path(__file__).resolve().parents[1] / "helpers"  # toy_eval, for the child processes too
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
import toy_eval  # noqa: E402
from toy_eval import ToyProblem, calls  # noqa: E402

H = "f" * 64
# Owners on another host: only their leases tell whether they are alive.
A, B = "elsewhere/1/a", "elsewhere/2/b"


def _ok(key_value: float, f: float = 1.0, fp: str = H) -> SampleRecord:
    return SampleRecord(design=(key_value, 1.0), fingerprint=fp, status="ok", outputs={"f": f})


def _k(v: float) -> str:
    return design_key((v, 1.0))


def test_claims_exclude_stored_and_validly_claimed_designs(tmp_path):
    k1, k2, k3, k4, k5 = (_k(v) for v in (1, 2, 3, 4, 5))
    with SampleStore(tmp_path / "s.sqlite") as store:
        assert store.claim(H, [k1, k2], A, 60.0) == [k1, k2]
        assert store.claim(H, [k1, k2, k3, k4], B, 60.0, limit=1) == [k3]
        assert store.claim(H, [k1, k2, k3, k4], B, 60.0) == [k3, k4]  # its own claims are renewed
        assert store.claim("other" * 8, [k1], B, 60.0) == [k1]  # claims are per fingerprint
        assert {(c.key, c.owner) for c in store.claims(H)} == {(k1, A), (k2, A), (k3, B), (k4, B)}

        assert store.put(_ok(1.0))  # storing a result drops its claim
        assert {c.key for c in store.claims(H)} == {k2, k3, k4}
        assert store.claim(H, [k1], B, 60.0) == []  # stored: nothing to claim

        assert store.release_claims(A) == 1 and store.claim(H, [k2], B, 60.0) == [k2]
        assert store.release_claims(B, [k2]) == 1 and store.release_claims(B) == 3  # k3, k4 and the other fp

        assert store.claim(H, [k5], A, 0.3) == [k5]
        assert store.claim(H, [k5], B, 60.0) == []
        time.sleep(0.4)
        assert store.claim(H, [k5], B, 60.0) == [k5]  # A's lease lapsed: taken over

        assert store.claim(H, [k4], A, 0.3) == [k4]
        assert store.renew_claims(A, 60.0) == 1
        time.sleep(0.4)
        assert store.claim(H, [k4], B, 60.0) == []  # renewed: still A's


def test_redo_failed_before_claims_and_drops_only_older_failures(tmp_path):
    with SampleStore(tmp_path / "s.sqlite") as store:
        old = SampleRecord(design=(1.0, 1.0), fingerprint=H, status="failed", error="E: x",
                           timestamp="2026-01-01T00:00:00.000Z")
        new = SampleRecord(design=(2.0, 1.0), fingerprint=H, status="failed", error="E: x",
                           timestamp="2026-01-03T00:00:00.000Z")
        store.put_many([old, new, _ok(3.0)])
        cut = "2026-01-02T00:00:00.000Z"
        assert store.claim(H, [_k(1), _k(2), _k(3)], A, 60.0) == []
        assert store.claim(H, [_k(1), _k(2), _k(3)], A, 60.0, redo_failed_before=cut) == [_k(1)]
        assert store.get((1.0, 1.0), H) is None and store.get((2.0, 1.0), H) == new
        assert store.count(H) == 2


CLAIMER = """
import sys
from mechopt.runs.store import SampleStore, new_owner
owner = new_owner()
with SampleStore(sys.argv[1]) as store:
    store.claim(sys.argv[2], [sys.argv[3]], owner, 600.0)
print(owner, flush=True)
sys.stdin.readline()  # hold on until killed
"""


def test_claim_of_a_killed_process_on_this_host_is_taken_over_at_once(tmp_path):
    path = tmp_path / "s.sqlite"
    SampleStore(path).close()
    proc = subprocess.Popen([sys.executable, "-c", CLAIMER, str(path), H, _k(1)], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    try:
        owner = proc.stdout.readline().strip()
        assert owner.split("/")[1] == str(proc.pid)
        me = new_owner()
        with SampleStore(path) as store:
            assert store.claim(H, [_k(1)], me, 60.0) == []  # alive, 600 s lease
            proc.send_signal(signal.SIGKILL)
            proc.wait(timeout=30)
            [claim] = store.claims(H)
            assert claim.owner == owner and claim.expires > time.time() + 500  # the lease is still valid...
            assert store.claim(H, [_k(1)], me, 60.0) == [_k(1)]  # ...but its process is gone
    finally:
        proc.kill()
        proc.wait()
        proc.stdin.close()
        proc.stdout.close()


def test_sampling_waits_for_a_design_another_run_is_evaluating(tmp_path):
    path = tmp_path / "s.sqlite"
    designs = toy_eval.random_designs(5, seed=21)
    counter = str(tmp_path / "calls.txt")
    problem = ToyProblem(counter=counter)
    fp = problem.fingerprint()
    theirs = SampleRecord(design=designs[0], fingerprint=fp, status="ok", outputs={"f": 123.0, "g": 4.0})

    def other_run() -> None:  # holds a claim on designs[0] and stores its result 0.5 s later
        with SampleStore(path) as store:
            time.sleep(0.5)
            store.put(theirs)

    with SampleStore(path) as store:
        assert store.claim(fp, [design_key(designs[0])], A, 30.0)
        thread = threading.Thread(target=other_run)
        thread.start()
        try:
            res = sample_designs(designs, problem, store, executor=InProcessExecutor(), progress=False)
        finally:
            thread.join()
        assert (res.n_cached, res.n_computed, res.n_waited) == (0, 4, 1)
        assert res.records[0] == theirs and res.wall_time_s >= 0.45
        assert store.claims() == []
    assert sorted(calls(counter)) == sorted(design_key(d) for d in designs[1:])


def test_sampling_takes_over_an_expired_claim(tmp_path):
    designs = toy_eval.random_designs(4, seed=22)
    counter = str(tmp_path / "calls.txt")
    problem = ToyProblem(counter=counter)
    with SampleStore(tmp_path / "s.sqlite") as store:
        assert store.claim(problem.fingerprint(), [design_key(designs[2])], A, 1.0)  # a run that died elsewhere
        res = sample_designs(designs, problem, store, executor=InProcessExecutor(), progress=False)
        assert (res.n_computed, res.n_waited) == (4, 0)
        assert res.wall_time_s >= 0.9  # it waited for the lease to lapse
        assert store.claims() == [] and store.count(problem.fingerprint()) == 4
    assert sorted(calls(counter)) == sorted(design_key(d) for d in designs)


def test_heartbeat_keeps_a_long_evaluation_claimed(tmp_path):
    path = tmp_path / "s.sqlite"
    design = (20.0, 70.0, 60.0)
    problem = ToyProblem(delay=1.5)
    out = {}

    def run() -> None:
        with SampleStore(path) as store:
            out["res"] = sample_designs([design], problem, store, executor=InProcessExecutor(), progress=False,
                                        lease_s=0.6)

    SampleStore(path).close()
    thread = threading.Thread(target=run)
    thread.start()
    try:
        with SampleStore(path) as store:
            deadline = time.monotonic() + 30
            while not store.claims():
                assert time.monotonic() < deadline
                time.sleep(0.01)
            time.sleep(1.0)  # longer than the lease: only the heartbeat keeps the claim valid
            assert store.claim(problem.fingerprint(), [design_key(design)], A, 60.0) == []
    finally:
        thread.join()
    assert out["res"].n_computed == 1 and out["res"].records[0].ok


TWO_RUNS = """
import json
import sys

sys.path.insert(0, {here!r})

import toy_eval
from mechopt.runs.executors import make_executor
from mechopt.runs.sampling import sample_designs
from mechopt.runs.store import SampleStore


def main():
    db, counter, n, delay, workers = sys.argv[1:]
    problem = toy_eval.ToyProblem(counter=counter, delay=float(delay))
    designs = toy_eval.random_designs(int(n), seed=31)
    with make_executor(workers=int(workers)) as ex:
        assert sorted(ex.map_unordered(abs, [-1, -2])) == [1, 2]  # workers started: time only the sampling
        print("ready", flush=True)
        sys.stdin.readline()
        with SampleStore(db) as store:
            res = sample_designs(designs, problem, store, executor=ex, progress=False)
    print(json.dumps(res.summary()), flush=True)


if __name__ == "__main__":
    main()
"""


def test_two_processes_sampling_the_same_designs_share_the_work(tmp_path):
    """Issue 10: two runs at once on one store both evaluated every design.  Now each design is evaluated once."""
    n, delay = 40, 0.1
    db, counter = tmp_path / "s.sqlite", str(tmp_path / "calls.txt")
    SampleStore(db).close()
    script = tmp_path / "run.py"
    script.write_text(TWO_RUNS.format(here=str(HERE)))
    # One run on a pool of two processes, the other in-process: claims are taken in batches of max_in_flight.
    procs = [subprocess.Popen([sys.executable, str(script), str(db), counter, str(n), str(delay), workers],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for workers in ("2", "1")]
    try:
        for p in procs:
            assert p.stdout.readline().strip() == "ready", p.communicate(timeout=60)
        for p in procs:  # go
            p.stdin.write("\n")
            p.stdin.flush()
        results = [p.communicate(timeout=120) for p in procs]
    finally:
        for p in procs:
            p.kill()
            p.wait()
    assert [p.returncode for p in procs] == [0, 0], [err for _, err in results]
    runs = [json.loads(out.strip().splitlines()[-1]) for out, _ in results]
    for run in runs:
        assert run["n_cached"] + run["n_computed"] + run["n_waited"] == n
    assert sum(run["n_computed"] for run in runs) == n  # no design evaluated by both
    assert all(run["n_computed"] >= 4 for run in runs), runs  # and both took a share
    keys = {design_key(d) for d in toy_eval.random_designs(n, seed=31)}
    assert Counter(calls(counter)) == Counter({k: 1 for k in keys})
    with SampleStore(db) as store:
        assert store.count() == n and {r.key for r in store.records()} == keys and store.claims() == []
    assert [run["executor"] for run in runs] == ["2 local processes", "in-process (1 worker)"]
    # Serial: 40 x 0.1 s = 4 s (the in-process run alone).  Together on 2 + 1 workers: about a third of that.
    assert max(run["wall_time_s"] for run in runs) < 4.0 * 0.85

