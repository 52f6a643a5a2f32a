"""sample_designs with real processes, a real Dask LocalCluster and a real SIGKILL mid-run."""

from __future__ import annotations

import functools
import os
import signal
import socket
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import pytest
from mechopt.errors import InputError
from mechopt.studies.executors import InProcessExecutor, ProcessExecutor, make_executor
from mechopt.studies.sampling import sample_designs
from mechopt.studies.store import SampleStore, design_key, settings_hash

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
# Worker processes import the toy simulators by module name; children inherit sys.path (spawn, forkserver).
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
import toy_eval  # noqa: E402

H = settings_hash({"engine": "toy", "version": 1})


def _calls(counter: Path) -> list[str]:
    return counter.read_text().split() if counter.exists() else []


def _fingerprint(result) -> list[tuple]:
    return [(r.key, r.status, r.t_rms, r.t_max, r.extra, r.error) for r in result.records]


def test_in_process_run_then_everything_cached(tmp_path):
    designs = toy_eval.random_designs(12, seed=1)
    counter = tmp_path / "calls.txt"
    evaluate = functools.partial(toy_eval.counting_eval, counter=str(counter))
    with SampleStore(tmp_path / "s.sqlite") as store:
        res = sample_designs(designs, evaluate, store, H, executor=make_executor(workers=1), progress=False)
        assert [r.design for r in res.records] == designs  # order of the request
        assert (res.n_requested, res.n_unique, res.n_cached, res.n_computed) == (12, 12, 0, 12)
        assert res.n_ok + res.n_infeasible == 12 and res.n_failed == 0
        assert res.executor == "in-process (1 worker)"
        ok = [r for r in res.records if r.ok]
        assert ok and all(r.extra == {"n_steps": 100, "torque_head": [0.0, r.t_rms, -r.t_rms]} for r in ok)
        assert all(r.wall_time_s is not None and r.wall_time_s >= 0 for r in res.records)
        assert store.count(H) == 12

        again = sample_designs(designs[::-1], evaluate, store, H, progress=False)
        assert (again.n_cached, again.n_computed, again.executor) == (12, 0, "")
        assert again.records == res.records[::-1]
    assert sorted(_calls(counter)) == sorted(design_key(d) for d in designs)  # each simulated once


def test_duplicates_within_a_request_are_simulated_once(tmp_path):
    d = (20.0, 70.0, 60.0)
    noisy = (20.0 + 1e-12, 70.0, 60.0 - 1e-12)
    counter = tmp_path / "calls.txt"
    evaluate = functools.partial(toy_eval.counting_eval, counter=str(counter))
    with SampleStore(tmp_path / "s.sqlite") as store:
        res = sample_designs([d, noisy, d], evaluate, store, H, executor=InProcessExecutor(), progress=False)
    assert (res.n_requested, res.n_unique, res.n_computed) == (3, 1, 1)
    assert res.records[0] == res.records[1] == res.records[2]
    assert _calls(counter) == [design_key(d)]


def test_settings_hash_isolates_runs(tmp_path):
    designs = toy_eval.random_designs(5, seed=2)
    counter = tmp_path / "calls.txt"
    evaluate = functools.partial(toy_eval.counting_eval, counter=str(counter))
    with SampleStore(tmp_path / "s.sqlite") as store:
        sample_designs(designs, evaluate, store, H, executor=InProcessExecutor(), progress=False)
        other = sample_designs(
            designs,
            evaluate,
            store,
            settings_hash({"engine": "toy", "version": 2}),
            executor=InProcessExecutor(),
            progress=False,
        )
        assert (other.n_cached, other.n_computed) == (0, 5)
        assert store.count() == 10
    assert len(_calls(counter)) == 10


def test_failures_are_recorded_and_the_run_goes_on(tmp_path):
    good = toy_eval.random_designs(6, seed=3)
    failing = (toy_eval.FAIL_OA, 70.0, 60.0)
    infeasible = (10.0, 200.0, 20.0)
    designs = [*good[:3], failing, infeasible, *good[3:]]
    counter = tmp_path / "calls.txt"
    evaluate = functools.partial(toy_eval.counting_eval, counter=str(counter))
    with SampleStore(tmp_path / "s.sqlite") as store, make_executor(workers=2) as ex:
        res = sample_designs(designs, evaluate, store, H, executor=ex, progress=False)
        by_key = {r.key: r for r in res.records}
        f = by_key[design_key(failing)]
        assert f.status == "failed" and f.t_rms is None
        assert f.error == f"RuntimeError: {toy_eval.FAIL_MESSAGE} at oa=13.0"  # one line
        i = by_key[design_key(infeasible)]
        assert i.status == "infeasible" and i.error.startswith("cannot assemble: |AB| = 200 mm")
        assert (res.n_failed, res.n_infeasible, res.n_computed) == (1, 1, 8)
        assert store.count(H, status="failed") == 1 and store.count(H, status="infeasible") == 1
        assert all(by_key[design_key(d)].ok for d in good if d[1] <= d[0] + d[2])

        # Failed and infeasible designs are stored: a rerun does not retry them.
        again = sample_designs(designs, evaluate, store, H, executor=ex, progress=False)
        assert (again.n_cached, again.n_computed, again.n_failed, again.n_infeasible) == (8, 0, 1, 1)
    assert len(_calls(counter)) == 8


def test_malformed_results_are_failed_records(tmp_path):
    designs = [(float(k), 5.0, 5.0) for k in (1, 2, 3, 4, 5)]
    with SampleStore(tmp_path / "s.sqlite") as store:
        res = sample_designs(designs, toy_eval.malformed_eval, store, H, executor=InProcessExecutor(), progress=False)
    errors = [r.error for r in res.records]
    assert [r.status for r in res.records] == ["failed"] * 4 + ["ok"]
    assert "expected a dict" in errors[0]
    assert "no 't_max'" in errors[1]
    assert "non-finite t_rms" in errors[2]
    assert "not JSON-serializable" in errors[3]


def test_processes_give_the_same_samples_as_in_process(tmp_path):
    designs = [*toy_eval.random_designs(16, seed=4), (toy_eval.FAIL_OA, 70.0, 60.0)]
    with SampleStore(tmp_path / "a.sqlite") as a, SampleStore(tmp_path / "b.sqlite") as b:
        serial = sample_designs(designs, toy_eval.toy_eval, a, H, executor=make_executor(1), progress=False)
        with make_executor(workers=2) as ex:
            assert isinstance(ex, ProcessExecutor) and ex.workers == 2
            parallel = sample_designs(designs, toy_eval.toy_eval, b, H, executor=ex, progress=False)
    assert _fingerprint(parallel) == _fingerprint(serial)
    assert parallel.executor == "2 local processes"


def test_executor_submits_at_most_workers_items_ahead(tmp_path):
    pulled = []

    def items():
        for i in range(20):
            pulled.append(i)
            yield -i

    for prefetch in (0, 1):
        pulled.clear()
        with make_executor(workers=2, prefetch=prefetch) as ex:
            assert ex.max_in_flight == 2 + prefetch
            results = ex.map_unordered(abs, items())
            first = next(results)
            # One result taken: the refill happens only when the next result is asked for.
            assert len(pulled) == 2 + prefetch
            rest = list(results)
        assert sorted([first, *rest]) == list(range(20))


def test_executor_argument_errors(tmp_path):
    with pytest.raises(InputError, match="positive integer"):
        make_executor(workers=0)
    with pytest.raises(InputError, match="non-negative integer"):
        make_executor(workers=2, prefetch=-1)
    assert isinstance(make_executor(workers=1), InProcessExecutor)
    with make_executor(workers=2) as ex, pytest.raises(InputError, match="picklable"):
        next(ex.map_unordered(lambda d: d, [(1.0, 2.0, 3.0)]))
    with pytest.raises(InputError, match="three lengths"):
        sample_designs([(1.0, 2.0)], toy_eval.toy_eval, SampleStore(tmp_path / "s.sqlite"), H)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_unreachable_dask_scheduler_is_a_one_line_input_error():
    pytest.importorskip("distributed")
    address = f"tcp://127.0.0.1:{_free_port()}"
    start = time.perf_counter()
    with pytest.raises(InputError, match=f"cannot reach the Dask scheduler at {address}") as info:
        make_executor(scheduler=address, connect_timeout=1.0)
    assert "\n" not in str(info.value)
    assert time.perf_counter() - start < 15


def test_dask_local_cluster_gives_the_same_samples_as_processes(tmp_path):
    distributed = pytest.importorskip("distributed")
    designs = [*toy_eval.random_designs(16, seed=5), (toy_eval.FAIL_OA, 70.0, 60.0), (10.0, 200.0, 20.0)]
    with SampleStore(tmp_path / "p.sqlite") as store, make_executor(workers=2) as ex:
        local = sample_designs(designs, toy_eval.toy_eval, store, H, executor=ex, progress=False)

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with SampleStore(tmp_path / "d.sqlite") as store:
            with make_executor(scheduler=cluster.scheduler_address) as ex:
                assert ex.workers == 2 and ex.description.startswith("Dask at tcp://")
                on_dask = sample_designs(designs, toy_eval.toy_eval, store, H, executor=ex, progress=False)
            assert store.count(H) == len(designs)
        # An existing client is used as is and left open for its owner.
        with distributed.Client(cluster, set_as_default=False) as client:
            with SampleStore(tmp_path / "c.sqlite") as store, make_executor(scheduler=client) as ex:
                small = sample_designs(designs[:4], toy_eval.toy_eval, store, H, executor=ex, progress=False)
            assert client.status == "running"
    assert _fingerprint(on_dask) == _fingerprint(local)
    assert (on_dask.n_failed, on_dask.n_infeasible) == (local.n_failed, local.n_infeasible)
    assert on_dask.n_failed == 1 and on_dask.n_infeasible >= 1 and on_dask.n_ok >= 10
    assert _fingerprint(small) == _fingerprint(local)[:4]


KILL_SCRIPT = """
import functools
import sys

sys.path[:0] = [{repo!r}, {here!r}]

import toy_eval
from mechopt.studies.executors import make_executor
from mechopt.studies.sampling import sample_designs
from mechopt.studies.store import SampleStore


def main():
    db, counter, h, n, workers, delay = sys.argv[1:]
    evaluate = functools.partial(toy_eval.counting_eval, counter=counter, delay=float(delay))
    designs = toy_eval.random_designs(int(n), seed=7)
    with SampleStore(db) as store, make_executor(workers=int(workers)) as ex:
        sample_designs(designs, evaluate, store, h, executor=ex, progress=False)


if __name__ == "__main__":  # the forkserver re-imports this file as __mp_main__
    main()
"""


def _live_group_members(pgid: int) -> list[int]:
    """Pids of the processes of a process group that are not zombies (Linux /proc)."""
    live = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()  # after "pid (comm) ": state ppid pgrp ...
        if int(fields[2]) == pgid and fields[0] != "Z":
            live.append(int(entry))
    return live


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc and POSIX signals")
def test_sigkill_mid_run_then_resume_loses_nothing_and_recomputes_nothing(tmp_path):
    n, workers, delay = 40, 2, 0.05
    db, counter = tmp_path / "s.sqlite", tmp_path / "calls.txt"
    script = tmp_path / "run.py"
    script.write_text(KILL_SCRIPT.format(repo=str(REPO), here=str(HERE)))
    proc = subprocess.Popen(
        [sys.executable, str(script), str(db), str(counter), H, str(n), str(workers), str(delay)],
        start_new_session=True,  # its own process group: the test can find (and clean up) its workers
    )
    try:
        deadline = time.monotonic() + 30
        while not db.exists():
            assert proc.poll() is None and time.monotonic() < deadline, "the run did not start"
            time.sleep(0.01)
        with SampleStore(db) as watcher:  # a second process reading the store during the run
            while watcher.count(H) < 8:
                assert proc.poll() is None and time.monotonic() < deadline, "the run ended before the kill"
                time.sleep(0.005)
        os.kill(proc.pid, signal.SIGKILL)
        assert proc.wait(timeout=10) == -signal.SIGKILL
        # Orphaned pool workers notice their parent's death and exit on their own.
        while _live_group_members(proc.pid):
            assert time.monotonic() < deadline, f"orphans left: {_live_group_members(proc.pid)}"
            time.sleep(0.05)
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass

    with SampleStore(db) as store:
        stored = {r.key for r in store.records(H)}
    calls_1 = Counter(_calls(counter))
    assert 8 <= len(stored) < n, "the kill should land mid-run"
    assert all(c == 1 for c in calls_1.values()), "a design was simulated twice in one run"
    assert stored <= set(calls_1)
    in_flight = set(calls_1) - stored  # started (or done) but not committed when killed
    assert len(in_flight) <= workers  # the executor's max_in_flight (no prefetch)

    with SampleStore(db) as store, make_executor(workers=workers) as ex:
        evaluate = functools.partial(toy_eval.counting_eval, counter=str(counter), delay=delay)
        designs = toy_eval.random_designs(n, seed=7)
        res = sample_designs(designs, evaluate, store, H, executor=ex, progress=False)
        assert (res.n_cached, res.n_computed) == (len(stored), n - len(stored))
        assert store.count(H) == n
        assert {r.key for r in store.records(H)} == {design_key(d) for d in designs}

    calls = Counter(_calls(counter))
    calls_2 = calls - calls_1
    assert not set(calls_2) & stored, "a stored design was simulated again"
    assert sum(calls.values()) <= n + len(in_flight) <= n + workers
    assert all(c == 1 or (c == 2 and k in in_flight) for k, c in calls.items())
