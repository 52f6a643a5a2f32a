"""The external-command simulator with real subprocesses: successes, every kind of failure, timeouts, kill -9, Dask.

Every test writes a small simulator script (:data:`SIM`) and a study file of kind "external" into ``tmp_path`` and
loads it through :func:`mechopt.load_study`, so the whole path — the TOML, the plug-in, the wrapper, the store —
is exercised.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from mechopt.errors import StudyError
from mechopt.runs.executors import make_executor
from mechopt.runs.sampling import sample_designs
from mechopt.runs.store import SampleStore, design_key
from mechopt.studies.catalogue import load_study

# f has its minimum 1 at (1.3, 0.7); special values of a (or b) make the simulator misbehave in one way each.
SIM = r'''
import json, os, subprocess, sys, time
files = "--files" in sys.argv
d = json.load(open("design.json")) if files else json.loads(sys.stdin.read())
a, b = d["a"], d["b"]
def note(var, text):
    if os.environ.get(var):
        fd = os.open(os.environ[var], os.O_WRONLY | os.O_APPEND | os.O_CREAT)
        os.write(fd, (text + "\n").encode())
        os.close(fd)
note("SIM_COUNTER", f"{a!r} {b!r}")
note("SIM_PIDS", str(os.getpid()))
time.sleep(float(os.environ.get("SIM_DELAY", "0")))
if a == 3.25:
    print("step 12: Newton iterations diverged", file=sys.stderr)
    sys.exit(3)
if a == 3.5:
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    note("SIM_PIDS", str(child.pid))
    time.sleep(60)
if a == 3.75:
    print("### license checked out ###")
    sys.exit(0)
if a == 0.25:
    print(json.dumps({"infeasible": "links do not assemble"}))
    sys.exit(0)
if a == 0.5:
    print(json.dumps({"f": 1.0}))
    sys.exit(0)
f = 1.0 + (a - 1.3) ** 2 + 2.0 * (b - 0.7) ** 2
if b == 3.9:
    f = float("nan")
out = json.dumps({"f": f, "g": a + b, "units": d["units"]})
if files:
    open("outputs.json", "w").write(out)
else:
    print("solver: converged")  # log lines before the JSON are allowed
    print(out)
'''

OK = [(1.0, 1.0), (2.0, 0.5), (1.3, 0.7)]
CASES = {
    "exit": (3.25, 1.0),
    "timeout": (3.5, 1.0),
    "garbage": (3.75, 1.0),
    "nan": (1.0, 3.9),
    "infeasible": (0.25, 1.0),
    "missing": (0.5, 1.0),
}


def f_exact(a: float, b: float) -> float:
    return 1.0 + (a - 1.3) ** 2 + 2.0 * (b - 0.7) ** 2


def write_study(folder: Path, *, exchange: str = "stdio", timeout: float = 2.0, env: dict | None = None,
                extra: str = "", script: str = SIM) -> Path:
    """A study of kind "external" over a, b in [0, 4] with the simulator script beside it."""
    (folder / "sim.py").write_text(script)
    env_line = ", ".join(f'{k} = "{v}"' for k, v in (env or {}).items())
    argv = '["{python}", "sim.py", "--files"]' if exchange == "files" else '["{python}", "sim.py"]'
    toml = folder / "study.toml"
    toml.write_text(f'''
name = "toy-external"
kind = "external"

[variables]
a = {{ lower = 0.0, upper = 4.0, unit = "mm", label = "a" }}
b = [0.0, 4.0]

[simulator]
command = {argv}
outputs = ["f", "g"]
objective = "f"
timeout_s = {timeout}
exchange = "{exchange}"
env = {{ {env_line} }}
{extra}
''')
    return toml


def lines(path: Path) -> list[str]:
    return path.read_text().splitlines() if path.is_file() else []


def alive(pid: int) -> bool:
    """True while ``pid`` exists and is not a zombie."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2] != "Z"


def wait_dead(pids: list[int], seconds: float = 10.0) -> list[int]:
    deadline = time.monotonic() + seconds
    while (left := [p for p in pids if alive(p)]) and time.monotonic() < deadline:
        time.sleep(0.05)
    return left


linux_only = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")


@linux_only
def test_every_failure_is_recorded_with_its_reason_and_not_simulated_again(tmp_path):
    counter, pids = tmp_path / "calls.txt", tmp_path / "pids.txt"
    problem = load_study(write_study(tmp_path, env={"SIM_COUNTER": counter, "SIM_PIDS": pids})).problem
    designs = [*OK, *CASES.values()]
    t0 = time.perf_counter()
    with SampleStore(tmp_path / "s.sqlite") as store, make_executor(workers=2) as ex:
        res = sample_designs(designs, problem, store, executor=ex, progress=False)
        elapsed = time.perf_counter() - t0
        by = dict(zip([*(f"ok{i}" for i in range(len(OK))), *CASES], res.records, strict=True))
        for i, (a, b) in enumerate(OK):
            r = by[f"ok{i}"]
            assert r.status == "ok" and r.outputs["f"] == pytest.approx(f_exact(a, b), rel=1e-14)
            assert r.outputs["g"] == pytest.approx(a + b) and r.outputs["units"] == {"a": "mm", "b": ""}
        assert by["exit"].status == "failed"
        assert "exit code 3" in by["exit"].error and "Newton iterations diverged" in by["exit"].error
        assert by["timeout"].status == "failed" and "timed out after 2 s" in by["timeout"].error
        assert by["garbage"].status == "failed" and "unparsable output" in by["garbage"].error
        assert "license checked out" in by["garbage"].error and "exit code 0" in by["garbage"].error
        assert by["nan"].status == "failed" and "'f' is not finite: nan" in by["nan"].error
        assert by["missing"].status == "failed" and "output 'g' missing" in by["missing"].error
        assert by["infeasible"].status == "infeasible" and by["infeasible"].error == "links do not assemble"
        assert all("\n" not in (r.error or "") for r in res.records)
        assert res.n_failed == 5 and res.n_infeasible == 1 and res.n_computed == len(designs)
        # The hung simulator and the process it started were killed with their group, at the timeout.
        assert elapsed < 30
        assert wait_dead([int(p) for p in lines(pids)], 5.0) == []
        n_calls = len(lines(counter))
        assert n_calls == len(designs)

        again = sample_designs(designs, problem, store, executor=ex, progress=False)
        assert again.n_computed == 0 and again.n_cached == len(designs)
        assert len(lines(counter)) == n_calls  # nothing simulated again, failures included
        assert [r.error for r in again.records] == [r.error for r in res.records]

        retry = sample_designs(designs, problem, store, executor=ex, progress=False, retry_failed=True)
        assert retry.n_computed == 5  # only the failures
        assert Counter(lines(counter)[n_calls:]) == Counter(f"{a!r} {b!r}" for k, (a, b) in CASES.items()
                                                            if k != "infeasible")


def test_files_exchange_gives_the_stdio_outputs_and_keeps_failed_work_folders(tmp_path):
    stdio_dir, files_dir = tmp_path / "stdio", tmp_path / "files"
    stdio_dir.mkdir()
    files_dir.mkdir()
    p_stdio = load_study(write_study(stdio_dir)).problem
    p_files = load_study(write_study(files_dir, exchange="files", extra='workdir = "runs"')).problem
    x = np.array([2.0, 0.5])
    assert p_files.evaluate(x) == p_stdio.evaluate(x)
    runs = files_dir / "runs"
    assert runs.is_dir() and not any(runs.iterdir())  # a successful design's folder is removed (keep = "failed")
    with SampleStore(tmp_path / "s.sqlite") as store:
        rec = sample_designs([CASES["exit"]], p_files, store, executor=make_executor(workers=1), progress=False)
    (kept,) = runs.iterdir()
    assert str(kept) in rec.records[0].error
    assert json.loads((kept / "design.json").read_text()) == {"a": 3.25, "b": 1.0, "units": {"a": "mm", "b": ""}}
    assert "Newton iterations diverged" in (kept / "stderr.txt").read_text()


def test_fingerprint_follows_the_script_exchange_and_env_but_not_the_timeout(tmp_path):
    toml = write_study(tmp_path, env={"LICENSE": "secret-123"})
    first = load_study(toml).problem
    fp = first.fingerprint()
    assert "secret-123" not in json.dumps(first.settings())  # licence keys enter the hash, not result.json
    assert load_study(write_study(tmp_path, env={"LICENSE": "secret-123"}, timeout=99)).problem.fingerprint() == fp
    assert load_study(write_study(tmp_path, env={"LICENSE": "other"})).problem.fingerprint() != fp
    assert load_study(write_study(tmp_path, env={"LICENSE": "secret-123"}, exchange="files")
                      ).problem.fingerprint() != fp
    write_study(tmp_path, env={"LICENSE": "secret-123"}, script=SIM + "\n# a fix in the user's script\n")
    assert load_study(toml).problem.fingerprint() != fp


@pytest.mark.parametrize(("simulator", "expected"), [
    ('command = "python sim.py"\noutputs = ["f"]', "never a shell string"),
    ('command = ["python", "sim.py"]\ncallable = "sim:run"\noutputs = ["f"]', "exactly one of command"),
    ('command = ["python", "sim.py"]\noutputs = ["f"]\nobjective = "h"', "simulator.objective = 'h'"),
    ('command = ["python", "sim.py"]\noutputs = []', "simulator.outputs"),
    ('command = ["python", "sim.py"]\noutputs = ["f"]\ntimeout = 3', "unknown key simulator.timeout"),
    ('command = ["python", "sim.py"]\noutputs = ["f"]\nexchange = "pipes"', "expected one of stdio, files"),
    ('callable = "nowhere_module:run"\noutputs = ["f"]', "module 'nowhere_module' not found"),
    ('callable = "sim:run"\noutputs = ["f"]\ntimeout_s = 3', "applies to a command"),
])
def test_a_bad_simulator_section_is_a_one_line_study_error(tmp_path, simulator, expected):
    toml = tmp_path / "study.toml"
    toml.write_text(f'kind = "external"\n[variables]\na = [0.0, 1.0]\nb = [0.0, 1.0]\n[simulator]\n{simulator}\n')
    (tmp_path / "sim.py").write_text("def run(d):\n    return {'f': 0.0}\n")
    with pytest.raises(StudyError, match="study.toml") as info:
        load_study(toml)
    assert expected in str(info.value) and "\n" not in str(info.value)


KILL_SCRIPT = r'''
import json, sys
from mechopt.studies.catalogue import load_study
from mechopt.runs.executors import make_executor
from mechopt.runs.sampling import sample_designs
from mechopt.runs.store import SampleStore
if __name__ == "__main__":  # the worker processes import this module: no run there
    problem = load_study(sys.argv[1]).problem
    with SampleStore(sys.argv[2]) as store, make_executor(workers=2) as ex:
        sample_designs(json.loads(sys.argv[3]), problem, store, executor=ex, progress=False)
'''


@linux_only
def test_kill_9_mid_run_loses_no_finished_design_and_leaves_no_simulator_behind(tmp_path):
    counter, pids = tmp_path / "calls.txt", tmp_path / "pids.txt"
    toml = write_study(tmp_path, env={"SIM_COUNTER": counter, "SIM_PIDS": pids, "SIM_DELAY": "0.3"})
    problem = load_study(toml).problem
    fp = problem.fingerprint()
    rng = np.random.default_rng(7)
    designs = [tuple(map(float, d)) for d in np.round(rng.uniform(1.0, 3.0, (24, 2)), 6)]
    db = tmp_path / "s.sqlite"
    (tmp_path / "run.py").write_text(KILL_SCRIPT)
    proc = subprocess.Popen([sys.executable, str(tmp_path / "run.py"), str(toml), str(db), json.dumps(designs)],
                            start_new_session=True, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 90
        while not db.exists():
            assert proc.poll() is None and time.monotonic() < deadline, "the run did not start"
            time.sleep(0.02)
        with SampleStore(db) as watcher:
            while watcher.count(fp) < 6:
                assert proc.poll() is None and time.monotonic() < deadline, "the run ended before the kill"
                time.sleep(0.01)
        # Simulators in flight at the kill: each finishes its current sleep, or dies with its worker.
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
        started = [int(p) for p in lines(pids)]
        # The simulators run in sessions of their own (out of reach of a group kill): they must die with their
        # worker (PR_SET_PDEATHSIG), which dies with the run.
        assert wait_dead(started, 10.0) == []
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.stderr.close()
    with SampleStore(db) as store:
        stored = {r.key for r in store.records(fp)}
        calls_1 = len(lines(counter))
        assert 6 <= len(stored) < len(designs)
        assert calls_1 - len(stored) <= 2  # at most one design in flight per worker was lost
        res = sample_designs(designs, problem, store, executor=make_executor(workers=2), progress=False)
    assert res.n_cached == len(stored) and res.n_computed == len(designs) - len(stored)
    assert all(r.ok for r in res.records)
    called_again = {design_key(tuple(map(float, line.split()))) for line in lines(counter)[calls_1:]}
    assert not called_again & stored  # no finished design simulated twice


def test_dask_local_cluster_gives_the_same_samples_as_in_process(tmp_path):
    distributed = pytest.importorskip("distributed")
    problem = load_study(write_study(tmp_path, timeout=5.0)).problem
    designs = [*OK, CASES["exit"], CASES["nan"], CASES["infeasible"], (0.75, 2.25), (3.0, 0.1)]
    with SampleStore(tmp_path / "local.sqlite") as store:
        local = sample_designs(designs, problem, store, executor=make_executor(workers=1), progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with SampleStore(tmp_path / "dask.sqlite") as store, make_executor(scheduler=cluster) as ex:
            assert ex.description.startswith("Dask at tcp://")
            dask = sample_designs(designs, problem, store, executor=ex, progress=False)
    assert [(r.status, r.outputs, r.error) for r in dask.records] == \
        [(r.status, r.outputs, r.error) for r in local.records]
    assert [r.status for r in local.records].count("ok") == 5
