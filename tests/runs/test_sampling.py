"""sample_designs with real processes, a real Dask LocalCluster, a real SIGKILL and a real Ctrl-C mid-run."""

from __future__ import annotations

import contextlib
import math
import os
import signal
import socket
import sqlite3
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import pytest

from mechopt.errors import InputError
from mechopt.runs.executors import InProcessExecutor, ProcessExecutor, make_executor
from mechopt.runs.sampling import sample_designs
from mechopt.runs.store import SampleStore, design_key

HERE = Path(__file__).resolve().parents[1] / "helpers"  # toy_eval, for the child processes too
# Worker processes import the toy problems by module name; children inherit sys.path (spawn, forkserver).
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
import toy_eval  # noqa: E402
from toy_eval import ToyProblem, calls, expected_outputs  # noqa: E402

FAILING = (toy_eval.FAIL_A, 70.0, 60.0)
INFEASIBLE = (10.0, 200.0, 20.0)


def _matches(outputs: dict, expected: dict) -> bool:
    """Same keys, and every number (or list of numbers) equal to 1e-14 relative."""
    return outputs.keys() == expected.keys() and all(
        outputs[k] == pytest.approx(v, rel=1e-14) for k, v in expected.items()
    )


def _samples(result) -> list[tuple]:
    return [(r.key, r.status, r.outputs, r.error) for r in result.records]


def test_in_process_run_then_everything_cached(tmp_path):
    designs = toy_eval.random_designs(12, seed=1)
    counter = str(tmp_path / "calls.txt")
    problem = ToyProblem(counter=counter)
    with SampleStore(tmp_path / "s.sqlite") as store:
        res = sample_designs(designs, problem, store, executor=make_executor(workers=1), progress=False)
        assert [r.design for r in res.records] == designs  # order of the request
        assert (res.n_requested, res.n_unique, res.n_cached, res.n_computed, res.n_waited) == (12, 12, 0, 12, 0)
        assert res.n_ok + res.n_infeasible == 12 and res.n_failed == 0 and res.n_ok >= 8
        assert res.executor == "in-process (1 worker)"
        for design, r in zip(designs, res.records, strict=True):
            assert r.fingerprint == problem.fingerprint()
            assert r.wall_time_s is not None and r.wall_time_s >= 0
            if design[1] > design[0] + design[2]:
                assert r.status == "infeasible" and r.outputs == {} and r.error.startswith("cannot assemble")
            else:
                assert r.ok and _matches(r.outputs, expected_outputs(design))
                assert r.value("f") == pytest.approx(expected_outputs(design)["f"], rel=1e-15)
        assert store.count(problem.fingerprint()) == 12

        again = sample_designs(designs[::-1], problem, store, progress=False)
        assert (again.n_cached, again.n_computed, again.n_waited, again.executor) == (12, 0, 0, "")
        assert again.records == res.records[::-1]
        assert store.claims() == []
    assert sorted(calls(counter)) == sorted(design_key(d) for d in designs)  # each evaluated once


def test_duplicates_within_a_request_are_evaluated_once(tmp_path):
    d = (20.0, 70.0, 60.0)
    noisy = (20.0 + 1e-12, 70.0, 60.0 - 1e-12)
    counter = str(tmp_path / "calls.txt")
    with SampleStore(tmp_path / "s.sqlite") as store:
        res = sample_designs([d, noisy, d], ToyProblem(counter=counter), store, executor=InProcessExecutor(),
                             progress=False)
    assert (res.n_requested, res.n_unique, res.n_computed) == (3, 1, 1)
    assert res.records[0] == res.records[1] == res.records[2]
    assert calls(counter) == [design_key(d)]


def test_fingerprint_isolates_problems_and_settings(tmp_path):
    designs = toy_eval.random_designs(5, seed=2)
    counter = str(tmp_path / "calls.txt")
    with SampleStore(tmp_path / "s.sqlite") as store:
        one = sample_designs(designs, ToyProblem(counter=counter), store, executor=InProcessExecutor(),
                             progress=False)
        # A setting that changes the outputs changes the fingerprint; one that does not (delay) keeps it.
        assert ToyProblem(delay=0.5).fingerprint() == ToyProblem().fingerprint()
        two = sample_designs(designs, ToyProblem(scale=2.0, counter=counter), store, executor=InProcessExecutor(),
                             progress=False)
        assert (two.n_cached, two.n_computed) == (0, 5)
        assert store.count() == 10 and len(store.fingerprints()) == 2
        for a, b in zip(one.records, two.records, strict=True):
            if a.ok:
                assert b.value("f") == pytest.approx(2.0 * a.value("f"), rel=1e-14)
        # An explicit fingerprint overrides the problem's.
        mine = sample_designs(designs[:2], ToyProblem(counter=counter), store, fingerprint="mine", progress=False,
                              executor=InProcessExecutor())
        assert mine.n_computed == 2 and store.count("mine") == 2
    assert len(calls(counter)) == 12


def test_failures_are_recorded_and_the_run_goes_on(tmp_path):
    good = toy_eval.random_designs(6, seed=3)
    designs = [*good[:3], FAILING, INFEASIBLE, *good[3:]]
    counter = str(tmp_path / "calls.txt")
    problem = ToyProblem(counter=counter)
    with SampleStore(tmp_path / "s.sqlite") as store, make_executor(workers=2) as ex:
        res = sample_designs(designs, problem, store, executor=ex, progress=False)
        by_key = {r.key: r for r in res.records}
        f = by_key[design_key(FAILING)]
        assert f.status == "failed" and f.outputs == {} and math.isnan(f.value("f"))
        assert f.error == f"RuntimeError: {toy_eval.FAIL_MESSAGE} at a=13.0"  # one line
        i = by_key[design_key(INFEASIBLE)]
        assert i.status == "infeasible" and i.error == "cannot assemble: b = 200 mm > a + c = 30 mm"
        assert (res.n_failed, res.n_infeasible, res.n_computed) == (1, 1, 8)
        fp = problem.fingerprint()
        assert store.count(fp, status="failed") == 1 and store.count(fp, status="infeasible") == 1
        assert all(by_key[design_key(d)].ok for d in good if d[1] <= d[0] + d[2])

        # Failed and infeasible designs are stored: a rerun does not retry them.
        again = sample_designs(designs, problem, store, executor=ex, progress=False)
        assert (again.n_cached, again.n_computed, again.n_failed, again.n_infeasible) == (8, 0, 1, 1)
    assert len(calls(counter)) == 8


def test_retry_failed_evaluates_only_the_failed_designs_again_and_replaces_them(tmp_path):
    designs = [*toy_eval.random_designs(4, seed=8), FAILING, INFEASIBLE]
    counter = str(tmp_path / "calls.txt")
    with SampleStore(tmp_path / "s.sqlite") as store:
        first = sample_designs(designs, ToyProblem(counter=counter), store, executor=InProcessExecutor(),
                               progress=False)
        assert first.n_failed == 1
        # The evaluator is fixed (fail_a is a bug, not a setting: same fingerprint), but failures are reused by
        # default...
        fixed = ToyProblem(counter=counter, fail_a=None)
        assert fixed.fingerprint() == ToyProblem().fingerprint()
        reused = sample_designs(designs, fixed, store, executor=InProcessExecutor(), progress=False)
        assert (reused.n_computed, reused.n_failed) == (0, 1)
        # ...and evaluated again, and replaced, on request.
        retried = sample_designs(designs, fixed, store, executor=InProcessExecutor(), progress=False,
                                 retry_failed=True)
        counts = (retried.n_cached, retried.n_computed, retried.n_failed, retried.n_infeasible)
        assert counts == (5, 1, 0, first.n_infeasible)
        new = retried.records[4]
        assert new.ok and _matches(new.outputs, expected_outputs(FAILING))
        assert new.timestamp > first.records[4].timestamp
        assert store.count() == 6 and store.count(status="failed") == 0
        assert store.get(FAILING, fixed.fingerprint()) == new
    assert Counter(calls(counter))[design_key(FAILING)] == 2 and len(calls(counter)) == 7


def test_malformed_results_are_failed_records_naming_the_key(tmp_path):
    designs = [(float(k), 5.0) for k in range(1, 8)]
    with SampleStore(tmp_path / "s.sqlite") as store:
        res = sample_designs(designs, toy_eval.MalformedProblem(), store, executor=InProcessExecutor(),
                             progress=False)
    errors = [r.error for r in res.records]
    assert [r.status for r in res.records] == ["failed"] * 6 + ["ok"]
    assert errors[0] == "evaluate returned float, expected a dict with outputs ['f', 'g']"
    assert errors[1] == "evaluate returned no output 'g' (got ['f'])"
    assert errors[2] == "output 'f' is not finite: nan"
    assert errors[3].startswith("output 'handle' is not JSON-serializable: object")
    assert errors[4] == "output 'f' is not a number: 'fast'"
    assert errors[5].startswith("output 'f' is not a number: array(")
    assert res.records[6].outputs == {"f": 1.5, "g": 2.0, "label": "fine"}


def test_processes_give_the_same_samples_as_in_process(tmp_path):
    designs = [*toy_eval.random_designs(16, seed=4), FAILING]
    with SampleStore(tmp_path / "a.sqlite") as a, SampleStore(tmp_path / "b.sqlite") as b:
        serial = sample_designs(designs, ToyProblem(), a, executor=make_executor(1), progress=False)
        with make_executor(workers=2) as ex:
            assert isinstance(ex, ProcessExecutor) and ex.workers == 2
            parallel = sample_designs(designs, ToyProblem(), b, executor=ex, progress=False)
    assert _samples(parallel) == _samples(serial)
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


def test_argument_errors_are_one_line(tmp_path):
    with pytest.raises(InputError, match="positive integer"):
        make_executor(workers=0)
    with pytest.raises(InputError, match="non-negative integer"):
        make_executor(workers=2, prefetch=-1)
    assert isinstance(make_executor(workers=1), InProcessExecutor)
    with make_executor(workers=2) as ex, pytest.raises(InputError, match="picklable"):
        next(ex.map_unordered(lambda d: d, [(1.0, 2.0, 3.0)]))
    with SampleStore(tmp_path / "s.sqlite") as store:
        with pytest.raises(InputError, match="must have 3 values, got 2"):
            sample_designs([(1.0, 2.0)], ToyProblem(), store)
        with pytest.raises(InputError, match="lease_s"):
            sample_designs([(20.0, 70.0, 60.0)], ToyProblem(), store, lease_s=0)
        assert store.count() == 0 and store.claims() == []


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
    designs = [*toy_eval.random_designs(16, seed=5), FAILING, INFEASIBLE]
    with SampleStore(tmp_path / "p.sqlite") as store, make_executor(workers=2) as ex:
        local = sample_designs(designs, ToyProblem(), store, executor=ex, progress=False)

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with SampleStore(tmp_path / "d.sqlite") as store:
            with make_executor(scheduler=cluster.scheduler_address) as ex:
                assert ex.workers == 2 and ex.description.startswith("Dask at tcp://")
                on_dask = sample_designs(designs, ToyProblem(), store, executor=ex, progress=False)
            assert store.count() == len(designs) and store.claims() == []
        # An existing client is used as is and left open for its owner.
        with distributed.Client(cluster, set_as_default=False) as client:
            with SampleStore(tmp_path / "c.sqlite") as store, make_executor(scheduler=client) as ex:
                small = sample_designs(designs[:4], ToyProblem(), store, executor=ex, progress=False)
            assert client.status == "running"
    assert _samples(on_dask) == _samples(local)
    assert (on_dask.n_failed, on_dask.n_infeasible) == (local.n_failed, local.n_infeasible)
    assert on_dask.n_failed == 1 and on_dask.n_infeasible >= 1 and on_dask.n_ok >= 10
    assert _samples(small) == _samples(local)[:4]


def _integrity(path: Path) -> str:
    with contextlib.closing(sqlite3.connect(path)) as conn:
        return conn.execute("PRAGMA integrity_check").fetchone()[0]


def test_keyboard_interrupt_leaves_an_intact_store_and_no_claim(tmp_path):
    designs = toy_eval.random_designs(10, seed=9)
    path = tmp_path / "s.sqlite"
    fp = ToyProblem().fingerprint()
    with SampleStore(path) as store:
        with pytest.raises(KeyboardInterrupt):
            sample_designs(designs, toy_eval.InterruptingProblem(stop_after=4), store, fingerprint=fp,
                           executor=InProcessExecutor(), progress=False)
        assert store.count(fp) == 4 and store.claims() == []
        assert _integrity(path) == "ok"
        res = sample_designs(designs, ToyProblem(), store, executor=InProcessExecutor(), progress=False)
        assert (res.n_cached, res.n_computed, res.n_waited) == (4, 6, 0)


RUN_SCRIPT = """
import sys

sys.path.insert(0, {here!r})

import toy_eval
from mechopt.runs.executors import make_executor
from mechopt.runs.sampling import sample_designs
from mechopt.runs.store import SampleStore


def main():
    db, counter, n, workers, delay = sys.argv[1:]
    problem = toy_eval.ToyProblem(counter=counter, delay=float(delay))
    designs = toy_eval.random_designs(int(n), seed=7)
    with SampleStore(db) as store, make_executor(workers=int(workers)) as ex:
        res = sample_designs(designs, problem, store, executor=ex, progress=False)
    print(res.n_computed)


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


def _interrupt_mid_run(tmp_path: Path, sig: int, n: int, workers: int, delay: float) -> tuple[set[str], Counter]:
    """Run a sampling script, send ``sig`` to it once 8 results are stored; return the stored keys and calls."""
    db, counter = tmp_path / "s.sqlite", tmp_path / "calls.txt"
    script = tmp_path / "run.py"
    script.write_text(RUN_SCRIPT.format(here=str(HERE)))
    proc = subprocess.Popen(
        [sys.executable, str(script), str(db), str(counter), str(n), str(workers), str(delay)],
        start_new_session=True,  # its own process group: the test can find (and clean up) its workers
        stderr=subprocess.PIPE,
        # Started from a background job, the child would inherit SIGINT ignored (no KeyboardInterrupt at all).
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    fp = ToyProblem().fingerprint()
    try:
        deadline = time.monotonic() + 120  # the imports alone take seconds on a loaded machine
        while not db.exists():
            assert proc.poll() is None and time.monotonic() < deadline, "the run did not start"
            time.sleep(0.01)
        with SampleStore(db) as watcher:  # a second process reading the store during the run
            while watcher.count(fp) < 8:
                assert proc.poll() is None and time.monotonic() < deadline, "the run ended before the signal"
                time.sleep(0.005)
        os.kill(proc.pid, sig)
        proc.wait(timeout=30)
        # Orphaned pool workers notice their parent's death (or shutdown) and exit on their own.
        while _live_group_members(proc.pid):
            assert time.monotonic() < deadline, f"orphans left: {_live_group_members(proc.pid)}"
            time.sleep(0.05)
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.stderr.close()
    assert proc.returncode != 0
    with SampleStore(db) as store:
        stored = {r.key for r in store.records(fp)}
    return stored, Counter(calls(counter))


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc and POSIX signals")
def test_sigkill_mid_run_then_resume_loses_nothing_and_recomputes_nothing(tmp_path):
    n, workers, delay = 40, 2, 0.05
    stored, calls_1 = _interrupt_mid_run(tmp_path, signal.SIGKILL, n, workers, delay)
    db, counter = tmp_path / "s.sqlite", str(tmp_path / "calls.txt")
    assert 8 <= len(stored) < n, "the kill should land mid-run"
    assert all(c == 1 for c in calls_1.values()), "a design was evaluated twice in one run"
    assert stored <= set(calls_1)
    in_flight = set(calls_1) - stored  # started (or done) but not committed when killed
    assert len(in_flight) <= workers  # the executor's max_in_flight (no prefetch)
    with SampleStore(db) as store:
        # The dead run's claims are left behind: those of the designs in flight, and of the next few claimed.
        dead = store.claims()
        assert in_flight <= {c.key for c in dead} and 1 <= len(dead) <= 2 * workers
        assert all(c.expires > time.time() + 60 for c in dead)  # valid leases (120 s)

    with SampleStore(db) as store, make_executor(workers=workers) as ex:
        problem = ToyProblem(counter=counter, delay=delay)
        designs = toy_eval.random_designs(n, seed=7)
        res = sample_designs(designs, problem, store, executor=ex, progress=False)
        # Taken over at once (their process is gone), not after the 120 s lease.
        assert (res.n_cached, res.n_computed, res.n_waited) == (len(stored), n - len(stored), 0)
        assert res.wall_time_s < 60
        assert store.count(problem.fingerprint()) == n and store.claims() == []
        assert {r.key for r in store.records(problem.fingerprint())} == {design_key(d) for d in designs}

    all_calls = Counter(calls(counter))
    calls_2 = all_calls - calls_1
    assert not set(calls_2) & stored, "a stored design was evaluated again"
    assert sum(all_calls.values()) <= n + len(in_flight) <= n + workers
    assert all(c == 1 or (c == 2 and k in in_flight) for k, c in all_calls.items())
    assert _integrity(db) == "ok"


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc and POSIX signals")
def test_ctrl_c_mid_run_releases_claims_and_keeps_every_result(tmp_path):
    n, workers, delay = 40, 2, 0.05
    stored, calls_1 = _interrupt_mid_run(tmp_path, signal.SIGINT, n, workers, delay)
    db, counter = tmp_path / "s.sqlite", str(tmp_path / "calls.txt")
    assert 8 <= len(stored) < n
    assert _integrity(db) == "ok"
    with SampleStore(db) as store:
        assert store.claims() == []  # released on the way out
        res = sample_designs(toy_eval.random_designs(n, seed=7), ToyProblem(counter=counter), store,
                             executor=InProcessExecutor(), progress=False)
        assert (res.n_cached, res.n_computed) == (len(stored), n - len(stored))
    assert not (Counter(calls(counter)) - calls_1).keys() & stored


IDLE_POOL_SCRIPT = """
import sys, time
from mechopt.runs.executors import make_executor
with make_executor(workers=2) as ex:
    list(ex.map_unordered(abs, [-1, -2, -3, -4]))
    try:
        print("ready", flush=True)
        time.sleep(120)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
"""


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs POSIX process groups")
def test_a_terminal_ctrl_c_is_left_to_the_main_process(tmp_path):
    # A terminal sends SIGINT to the whole process group: idle pool workers printed a KeyboardInterrupt traceback
    # each under the run's one line.
    proc = subprocess.Popen([sys.executable, "-c", IDLE_POOL_SCRIPT], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        assert proc.stdout.readline().strip() == "ready"
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
    assert err.strip() == "interrupted", err


def test_a_script_that_starts_workers_without_a_main_guard_is_told_why_they_died(tmp_path):
    # Each worker process would re-run an unguarded script's top level, and Python would stop it at start: the
    # script is told so in one line before any worker starts (issue 52; tests/runs/test_worker_startup.py).
    script = tmp_path / "unguarded.py"
    script.write_text(
        "import mechopt\n"
        "from mechopt.studies.benchmark_functions import Hartmann3\n"
        "mechopt.minimize(Hartmann3(), budget=10, seed=0, workers=2)\n"
    )
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120,
                          cwd=tmp_path)
    assert proc.returncode != 0
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mechopt: error: workers = 2 start processes"), proc.stderr
    assert 'if __name__ == "__main__":' in lines[0]
