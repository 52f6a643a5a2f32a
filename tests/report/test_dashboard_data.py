"""What the live page reads and computes, on real SQLite stores: the studies of a store, a study's progress, time
left, failures and front (checked against brute force), the figures, and the one-line refusals of bad paths."""

from __future__ import annotations

import contextlib
import json
import subprocess
import sys
from datetime import datetime, timedelta

import numpy as np
import pytest

import mechopt
from mechopt.errors import InputError
from mechopt.runs.run_journal import RunJournal, describe_run
from mechopt.runs.store import SampleRecord, SampleStore

pytest.importorskip("plotly")

from mechopt.report.dashboard.figures import front_figure, parallel_figure, progress_figure  # noqa: E402
from mechopt.report.dashboard.server import DashboardServer, study_json  # noqa: E402
from mechopt.report.dashboard.snapshot import non_dominated, snapshot  # noqa: E402
from mechopt.report.dashboard.store_reader import (  # noqa: E402
    find_store,
    list_studies,
    open_read_only,
    read_study,
)


class TwoGoals(mechopt.DesignProblem):
    name = "two-goals"
    variables = (mechopt.Variable("a", 0.0, 1.0, "mm"), mechopt.Variable("b", 0.0, 1.0, "mm"))
    outputs = ("f1", "f2")
    objective = "f1"
    objectives = ("f1", "f2")

    def evaluate(self, x):
        return {"f1": float(x[0]), "f2": float((1 - x[0]) ** 2 + x[1])}


class Plan:
    budget, new, seconds = 30, 30, None


def _fill(path, problem, designs, name, planned=30, fail_every=0):
    """A store with a journal and one record per design (every ``fail_every``-th a failure)."""
    fp = problem.fingerprint()
    journal = RunJournal(path, fp, name, describe_run(problem, Plan(), "auto", [f"study {name}", "plan: 30"]))
    journal.message("  a message")
    with SampleStore(path) as store:
        for i, x in enumerate(designs, start=1):
            if fail_every and i % fail_every == 0:
                store.put(SampleRecord(tuple(x), fp, "failed", error="the simulator exited with 3"))
            else:
                store.put(SampleRecord(tuple(x), fp, "ok", problem.evaluate(x)))
    return journal


def _read(path, fp, objective=None, now=None):
    with contextlib.closing(open_read_only(path)) as conn:
        return snapshot(read_study(conn, fp), objective, now)


def test_non_dominated_matches_brute_force():
    rng = np.random.default_rng(0)
    F = np.round(rng.random((60, 3)), 1)  # rounded: ties and equal rows happen
    brute = [not any(np.all(F[j] <= F[i]) and np.any(F[j] < F[i]) for j in range(len(F))) for i in range(len(F))]
    assert non_dominated(F).tolist() == brute
    assert non_dominated(np.array([[1.0, 2.0], [1.0, 2.0], [2.0, 1.0], [2.0, 2.0]])).tolist() == [1, 1, 1, 0]


def test_a_running_study_its_progress_failures_and_front(tmp_path):
    path = tmp_path / "s.sqlite"
    problem = TwoGoals()
    designs = np.random.default_rng(1).random((12, 2))
    journal = _fill(path, problem, designs, "two-goals", fail_every=4)
    with contextlib.closing(open_read_only(path)) as conn:
        started = read_study(conn, problem.fingerprint()).latest.started
    now = datetime.fromisoformat(started) + timedelta(seconds=24)
    snap = _read(path, problem.fingerprint(), now=now)
    s = snap.summary
    assert (s["state"], s["done"], s["planned"], s["held"]) == ("running", 12, 30, 0)
    assert s["left_s"] == pytest.approx((30 - 12) * 24 / 12)  # the run's average pace so far
    assert s["failures"] == {"failed": 3, "infeasible": 0, "reasons": [("failed: the simulator exited with 3", 3)]}
    assert s["plan"] == ["study two-goals", "plan: 30"] and s["messages"][0].endswith("  a message")
    ok = [i for i in range(12) if (i + 1) % 4]
    F = np.array([[designs[i, 0], (1 - designs[i, 0]) ** 2 + designs[i, 1]] for i in ok])
    best = int(np.argmin(F[:, 0]))
    assert s["best"]["index"] == ok[best] + 1 and s["best"]["outputs"]["f1"] == pytest.approx(F[best, 0])
    front = front_figure(snap)
    shown = {tuple(np.round(p, 9)) for p in zip(front.data[1].x, front.data[1].y, strict=True)}
    assert shown == {tuple(np.round(p, 9)) for p in F[non_dominated(F)]}
    parallel = parallel_figure(snap)
    assert [d.label for d in parallel.data[0].dimensions] == ["a (mm)", "b (mm)", "f1", "f2"]
    assert len(parallel.data[0].dimensions[0].values) == len(ok)
    progress = progress_figure(snap)
    assert len(progress.data) == 6  # each objective: its values, its best so far, the failures on it
    np.testing.assert_allclose(progress.data[1].y, np.fmin.accumulate(snap.values["f1"]))
    journal.finish()
    assert _read(path, problem.fingerprint()).summary["state"] == "finished"


def test_a_store_lists_each_study_and_one_objective_has_no_front(tmp_path):
    path = tmp_path / "s.sqlite"
    two = TwoGoals()
    one = TwoGoals()
    one.objectives = ("f2",)
    one.version = 2  # another fingerprint: another study in the same store
    _fill(path, two, [(0.1, 0.2), (0.5, 0.5)], "first").finish()
    _fill(path, one, [(0.3, 0.3)], "second")
    with contextlib.closing(open_read_only(path)) as conn:
        studies = list_studies(conn)
    assert [(s["name"], s["records"], s["ended"] is None) for s in studies] == [("second", 1, True),
                                                                                 ("first", 2, False)]
    body = json.loads(study_json(path, one.fingerprint(), None))
    assert body["study"]["objectives"] == ["f2"] and body["figures"]["front"] is None
    assert body["figures"]["parallel"]["data"][0]["type"] == "parcoords"
    # The page may colour by another output.
    assert json.loads(study_json(path, one.fingerprint(), "f1"))["study"]["objectives"] == ["f1", "f2"]


def test_an_output_folder_leads_to_its_store(tmp_path):
    (tmp_path / "out").mkdir()
    with pytest.raises(InputError, match=r"holds no samples.sqlite"):
        find_store(tmp_path / "out")
    with pytest.raises(InputError, match=r"no such file or folder"):
        find_store(tmp_path / "nowhere")
    SampleStore(tmp_path / "out" / "samples.sqlite").close()
    assert find_store(tmp_path / "out") == tmp_path / "out" / "samples.sqlite"
    (tmp_path / "notes.txt").write_text("hello " * 200)
    with pytest.raises(InputError, match="not a mechopt sample store"):
        open_read_only(tmp_path / "notes.txt")


def test_the_port_in_use_is_one_line(tmp_path):
    SampleStore(tmp_path / "s.sqlite").close()
    first = DashboardServer(tmp_path / "s.sqlite", port=0)
    try:
        port = first.httpd.server_address[1]
        assert first.url == f"http://127.0.0.1:{port}/"
        with pytest.raises(InputError, match=rf"--port {port}: the port is in use"):
            DashboardServer(tmp_path / "s.sqlite", port=port)
    finally:
        first.httpd.server_close()


@pytest.mark.parametrize(("args", "expected"), [(["nowhere.sqlite"], "no such file or folder"),
                                                (["s.sqlite", "--port", "70000"], "not a port number")])
def test_the_command_refuses_bad_input_in_one_line(tmp_path, args, expected):
    SampleStore(tmp_path / "s.sqlite").close()
    done = subprocess.run([sys.executable, "-m", "mechopt.cli.main", "dashboard", *args], cwd=tmp_path,
                          capture_output=True, text=True, timeout=60)
    assert done.returncode in (1, 2) and expected in done.stderr
    assert "Traceback" not in done.stderr and done.stdout == ""

