"""Every user mistake of the reliability issue gets one clear line on stderr and a non-zero exit, before any
simulation, and loses nothing already computed.  Commands run as real subprocesses, as a user types them."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

SMALL = ["--engine", "analytic", "--workers", "1", "--no-progress", "--lines-fit", "4", "--samples-per-line", "8",
         "--search-points", "100000", "--budget", "40"]


def mechopt(*args: str, cwd: Path | None = None, timeout: float = 300):
    """Run ``mechopt ARGS`` in a subprocess, as a user types it."""
    return subprocess.run([sys.executable, "-m", "mechopt.cli.main", *args], capture_output=True, text=True,
                          cwd=cwd, env={**os.environ, "MPLBACKEND": "Agg"}, timeout=timeout)


def one_line(proc, *expected: str) -> str:
    err = proc.stderr.strip()
    assert proc.returncode != 0, proc.stdout
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    for text in expected:
        assert text in err, err
    return err


def test_out_naming_a_file(tmp_path):
    f = tmp_path / "a_file"
    f.write_text("x")
    one_line(mechopt("study", "--out", str(f), *SMALL), "a_file", "expected a folder")
    one_line(mechopt("feasible", "--out", str(f)), "expected a folder")


def test_plot_with_an_unknown_suffix(tmp_path):
    one_line(mechopt("simulate", "--oa", "53", "--ab", "65", "--bc", "282", "--plot", str(tmp_path / "x.xyz")),
             "x.xyz", ".png")


@pytest.mark.parametrize("value", ["-1", "nan", "0"])
def test_bad_truth_grid(tmp_path, value):
    one_line(mechopt("study", "--out", str(tmp_path), "--truth-grid", value, *SMALL), "--truth-grid")


def test_bad_points_per_line_is_rejected_before_any_work(tmp_path):
    t0 = time.perf_counter()
    one_line(mechopt("study", "--out", str(tmp_path / "o"), "--points-per-line", "-1", *SMALL), "--points-per-line")
    assert not (tmp_path / "o").exists()  # nothing was started
    assert time.perf_counter() - t0 < 60


def test_damaged_result_and_model_files(tmp_path):
    (tmp_path / "result.json").write_text('{"optimum": {"des')
    one_line(mechopt("feasible", "--out", str(tmp_path)), "result.json", "damaged")
    (tmp_path / "result.json").unlink()
    (tmp_path / "model.json").write_text('{"format": "mechopt.studies.ObjectiveModel", "vers')
    one_line(mechopt("validate", "--out", str(tmp_path), *SMALL), "model.json", "--refit")


def test_a_store_with_garbage_in_the_middle(tmp_path):
    store = tmp_path / "s.sqlite"
    con = sqlite3.connect(store)
    con.execute("CREATE TABLE t (x TEXT)")
    con.executemany("INSERT INTO t VALUES (?)", [("y" * 500,)] * 200)
    con.commit()
    con.close()
    data = bytearray(store.read_bytes())
    data[len(data) // 2 : len(data) // 2 + 4096] = os.urandom(4096)
    store.write_bytes(bytes(data))
    one_line(mechopt("study", "--out", str(tmp_path / "o"), "--store", str(store), *SMALL), str(store.name))


def test_validation_lines_zero_means_no_validation_not_nan(tmp_path):
    from mechopt.cli.main import main

    assert main(["study", "--out", str(tmp_path), "--lines", "0", *SMALL]) == 0
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["validation"] is None
    assert "NaN" not in (tmp_path / "result.json").read_text()
    assert "## Validation" not in (tmp_path / "report.md").read_text()


@contextlib.contextmanager
def read_only(*paths: Path):
    """Make files and folders unwritable, even for root (``chattr +i``), for the duration of the block."""
    root = os.geteuid() == 0
    for path in paths:
        if root:
            subprocess.run(["chattr", "+i", str(path)], check=True)
        else:
            os.chmod(path, 0o555 if path.is_dir() else 0o444)
    try:
        yield
    finally:
        for path in paths:
            if root:
                subprocess.run(["chattr", "-i", str(path)], check=False)
            else:
                os.chmod(path, 0o755 if path.is_dir() else 0o644)


def test_read_only_folders_get_one_line_and_a_healthy_read_only_store_is_not_called_unusable(tmp_path):
    from mechopt.runs.sampling import sample_designs
    from mechopt.runs.store import SampleStore
    from mechopt.studies.catalogue import load_study

    ro = tmp_path / "ro"
    ro.mkdir()
    store = ro / "s.sqlite"
    problem = load_study("ventilator", {"engine": "analytic"}).problem
    with SampleStore(store) as db:  # a healthy store with a few samples
        assert sample_designs([(53.0, 65.0, 282.0), (40.0, 80.0, 270.0)], problem, db, progress=False).n_ok == 2
    for p in [p for p in ro.iterdir() if p != store]:  # -wal / -shm of the closed store, if any
        p.unlink()
    with read_only(store, ro):
        one_line(mechopt("study", "--out", str(ro / "out"), *SMALL), "cannot create", "read-only")
        one_line(mechopt("feasible", "--out", str(ro)), "read-only")
        one_line(mechopt("simulate", "--oa", "53", "--ab", "65", "--bc", "282", "--plot", str(ro / "p.png")),
                 "read-only")
        # A healthy store the user may read but not write: said to be read-only, not "not a usable store".
        err = one_line(mechopt("study", "--out", str(tmp_path / "again"), "--store", str(store), "--seed", "7",
                               *SMALL))
        assert "not a usable" not in err and "read-only" in err


def _sigint_default() -> None:
    # A test run started in the background (nohup, `cmd &`) inherits SIGINT ignored, and Python then installs no
    # KeyboardInterrupt handler: give the child the terminal's default, as a user's shell would.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _stored(store: Path) -> dict[str, int]:
    """Rows of the store by status ({} while it does not exist or is being created)."""
    if not store.exists():
        return {}
    try:
        with sqlite3.connect(store) as con:
            return dict(con.execute("SELECT status, COUNT(*) FROM samples GROUP BY status").fetchall())
    except sqlite3.Error:
        return {}


def _ctrl_c(args: list[str], ready, sig: int = signal.SIGINT,
            group: bool = True) -> tuple[subprocess.CompletedProcess, float]:
    """Run ``mechopt ARGS`` in a process group of its own and, once ``ready()``, send it ``sig``: by default a
    Ctrl-C, SIGINT to the whole group as a terminal sends it (the workers get it too); with ``group`` False to the
    main process alone (``kill``, ``timeout``, a batch scheduler).  The finished process and the seconds it took to
    exit."""
    proc = subprocess.Popen([sys.executable, "-m", "mechopt.cli.main", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env={**os.environ, "MPLBACKEND": "Agg"},
                            preexec_fn=_sigint_default, start_new_session=True)
    try:
        deadline = time.time() + 240
        while not ready() and proc.poll() is None and time.time() < deadline:
            time.sleep(0.5)
        assert proc.poll() is None and ready(), "the run ended, or never got ready, before the Ctrl-C"
        (os.killpg if group else os.kill)(proc.pid, sig)
        t0 = time.time()
        out, err = proc.communicate(timeout=120)
        return subprocess.CompletedProcess(proc.args, proc.returncode, out, err), time.time() - t0
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)


def _assert_interrupted(proc: subprocess.CompletedProcess, code: int = 130, word: str = "interrupted") -> None:
    assert proc.returncode == code, proc.stderr
    lines = [line for line in proc.stderr.strip().splitlines() if line.strip()]
    # One line: no traceback of the workers (nor of pymunk's callbacks), no warning of leaked semaphores.
    assert len(lines) == 1 and word in lines[0] and "Traceback" not in proc.stderr, proc.stderr


def test_ctrl_c_leaves_one_line_and_an_intact_store(tmp_path):
    store = tmp_path / "s.sqlite"
    proc, _ = _ctrl_c(["study", "--out", str(tmp_path / "o"), "--store", str(store), "--engine", "pymunk",
                       "--workers", "2", "--no-progress", "--lines-fit", "21", "--samples-per-line", "25"],
                      lambda: sum(_stored(store).values()) >= 5)
    _assert_interrupted(proc)
    with sqlite3.connect(store) as con:
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        assert con.execute("SELECT COUNT(*) FROM samples").fetchone()[0] >= 5


COMMAND_SLEEPING = """import json, sys, time
design = json.load(sys.stdin)
time.sleep(float(sys.argv[1]) if design["x"] > 0.5 else 0.0)
print(json.dumps({"f": (design["x"] - 0.3) ** 2 + (design["y"] - 0.6) ** 2}))
"""


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="a worker finds its programs in Linux /proc")
@pytest.mark.parametrize(("sig", "group", "code", "word"), [(signal.SIGINT, True, 130, "interrupted"),
                                                            (signal.SIGTERM, False, 143, "terminated (SIGTERM)")])
def test_a_stop_ends_the_programs_in_progress(tmp_path, sig, group, code, word):
    # A CAD run takes minutes; its program runs in a session of its own, out of the terminal's reach.  After a
    # Ctrl-C, or a SIGTERM to mechopt alone (`timeout`, a batch scheduler: Python's default ended the process on
    # the spot, its claims left in the store), the user waits neither for the program nor for its orphan, and its
    # killed run is not stored as a failure.
    (tmp_path / "sim.py").write_text(COMMAND_SLEEPING)
    (tmp_path / "slow.toml").write_text(
        'name = "slow"\nkind = "external"\n[variables]\nx = [0.0, 1.0]\ny = [0.0, 1.0]\n[simulator]\n'
        'command = ["{python}", "-S", "sim.py", "300"]\noutputs = ["f"]\n')
    store = tmp_path / "o" / "samples.sqlite"
    proc, seconds = _ctrl_c(["study", str(tmp_path / "slow.toml"), "--method", "auto", "--budget", "12",
                             "--workers", "2", "--out", str(tmp_path / "o"), "--no-progress"],
                            lambda: _stored(store).get("ok", 0) >= 1 and _running("sim.py 300"), sig, group)
    _assert_interrupted(proc, code, word)
    assert seconds < 60, seconds
    deadline = time.time() + 30
    while _running("sim.py 300") and time.time() < deadline:
        time.sleep(0.2)
    assert not _running("sim.py 300"), "a program outlived the run"
    assert "failed" not in _stored(store), _stored(store)
    with sqlite3.connect(store) as con:
        assert con.execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0


def _running(text: str) -> bool:
    """Whether a live process's command line contains ``text`` (Linux /proc)."""
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        with contextlib.suppress(OSError):
            if text in cmdline.read_bytes().replace(b"\0", b" ").decode(errors="replace"):
                return True
    return False


def test_budget_below_the_methods_minimum(tmp_path):
    # The study's own default method (sparse) and an explicit one: refused before the plan is printed, nothing
    # simulated, no output folder made.
    proc = mechopt("study", "ventilator", "--budget", "3", "--out", str(tmp_path / "v"), "--no-progress")
    one_line(proc, "budget = 3", "'sparse'", "= 7 simulations")
    assert not proc.stdout.strip(), proc.stdout
    proc = mechopt("study", "ventilator", "--budget", "20", "--method", "sparse-global", "--out", str(tmp_path / "g"),
                   "--no-progress")
    one_line(proc, "budget = 20", "10d = 30")
    assert not proc.stdout.strip(), proc.stdout  # not even the line that scales the study's plan to the budget
    one_line(mechopt("study", "hartmann6", "--budget", "10", "--out", str(tmp_path / "h"), "--no-progress"),
             "budget = 10", "'auto'", "2d + 2 = 14")
    assert not (tmp_path / "v").exists() and not (tmp_path / "h").exists()


def test_truth_and_feasible_make_no_folder_for_nothing(tmp_path):
    # A study with no batch evaluator: refused before the output folder is made.  A study with no constraints:
    # said in a line, and no flat one-colour figure drawn.
    one_line(mechopt("truth", "--study", "rowing", "--out", str(tmp_path / "r")), "no fast batch evaluator")
    proc = mechopt("feasible", "--study", "hartmann6", "--out", str(tmp_path / "h"))
    assert proc.returncode == 0 and "declares no constraints" in proc.stdout, proc.stdout + proc.stderr
    assert not (tmp_path / "r").exists() and not (tmp_path / "h").exists()


def test_a_study_with_a_folder_for_a_store_or_a_scheduler_nobody_listens_at_makes_no_folder(tmp_path):
    # Both were found only after the output folder, its figures folder and an empty store had been made.
    (tmp_path / "folder").mkdir()
    one_line(mechopt("study", "branin", "--budget", "12", "--store", str(tmp_path / "folder"), "--out",
                     str(tmp_path / "a")), f"--store {tmp_path / 'folder'} is a folder")
    one_line(mechopt("study", "branin", "--budget", "12", "--scheduler", "tcp://127.0.0.1:1", "--out",
                     str(tmp_path / "b")), "cannot reach the Dask scheduler at tcp://127.0.0.1:1")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_a_study_whose_every_simulation_fails_and_one_whose_line_model_hands_over(tmp_path):
    # A copied command study whose command is broken: the study said "a design must have finite values, got (nan,
    # nan, nan)" (auto) or raised AttributeError: pipeline (sparse, handed to auto), and the sparse run simulated 17
    # designs for a budget of 10 (the line plan's designs outside the box, clipped onto it by auto).
    assert mechopt("init", "ventilator-command", "--to", "vc", cwd=tmp_path).returncode == 0
    toml = tmp_path / "vc" / "study.toml"
    toml.write_text(toml.read_text().replace("simulate_ventilator.py", "nosuch.py").replace(
        'name = "ventilator-command"', 'name = "vc-broken"'))  # renamed, as init advises: its table was copied
    for method in ("auto", "sparse"):
        proc = mechopt("study", "vc/study.toml", "--method", method, "--budget", "10", "--workers", "1",
                       "--no-progress", "--out", method, cwd=tmp_path)
        one_line(proc, "the first 5 simulations all failed, the first with: SimulatorFailure: exit code 2",
                 "nosuch.py", f"recorded in {method}/samples.sqlite", "--retry-failed")
    # Without the early stop the whole budget is spent, and the study says so in one line too.
    proc = mechopt("study", "vc/study.toml", "--method", "auto", "--budget", "10", "--workers", "1",
                   "--no-progress", "--out", "all", "--stop-after-failures", "0", cwd=tmp_path)
    one_line(proc, "vc-broken: none of the 10 simulations succeeded, the first failed with: SimulatorFailure: "
             "exit code 2", "nosuch.py", "recorded in all/samples.sqlite")
    # Some simulations fail: the line model hands over to auto, and the study writes its report.
    proc = mechopt("study", "failing_hartmann3", "--method", "sparse", "--budget", "60", "--workers", "1",
                   "--no-progress", "--out", "fh", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    result = json.loads((tmp_path / "fh" / "result.json").read_text())
    assert "the line model could not be built" in result["message"] and result["simulations"]["optimisation"] == 60
