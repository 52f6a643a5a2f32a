"""The run journal in the sample store: what a run writes (description, messages, end) and reads back, on a real
SQLite file."""

from __future__ import annotations

import contextlib
import sqlite3

import pytest

import mechopt
from mechopt.errors import InputError
from mechopt.runs.run_journal import RunJournal, describe_run, read_messages, read_runs
from mechopt.runs.store import SampleRecord, SampleStore


class Bowl(mechopt.DesignProblem):
    name = "bowl"
    variables = (mechopt.Variable("a", 0.0, 2.0, "mm"), mechopt.Variable("b", -1.0, 1.0))
    outputs = ("f", "g")
    output_units = (("f", "N·m"),)
    objective = "f"

    def evaluate(self, x):
        return {"f": float(x[0] ** 2 + x[1] ** 2), "g": float(x[0])}


class Plan:
    budget, new, total, seconds = 40, 45, 47, 12.5


def _read(path):
    with contextlib.closing(sqlite3.connect(path)) as conn:
        runs = read_runs(conn)
        return runs, {run.id: read_messages(conn, run.id) for run in runs}


def test_a_run_describes_itself_logs_its_lines_and_its_end(tmp_path):
    path = tmp_path / "s.sqlite"
    problem = Bowl()
    with SampleStore(path) as store:
        store.put(SampleRecord((1.0, 0.0), problem.fingerprint(), "ok", {"f": 1.0, "g": 1.0}))
        assert _read(path) == ([], {})  # a store without a journal reads as no run
        described = describe_run(problem, Plan(), "sparse", ["study bowl", "plan: budget 40"], tmp_path / "out",
                                 held=store.count(problem.fingerprint()))
    journal = RunJournal(path, problem.fingerprint(), "bowl", described)
    printed = []
    log = journal.tee(printed.append)
    log("  global model: 30 samples")
    log("  refinement: 10 simulations")
    (run,), messages = _read(path)
    assert (run.name, run.fingerprint, run.ended, run.outcome) == ("bowl", problem.fingerprint(), None, None)
    assert run.description["variables"] == [{"name": "a", "unit": "mm", "lower": 0.0, "upper": 2.0},
                                            {"name": "b", "unit": "", "lower": -1.0, "upper": 1.0}]
    assert run.description["objectives"] == ["f"]
    assert run.description["units"] == {"f": "N·m"}
    assert (run.description["planned"], run.description["budget"], run.description["held"]) == (45, 40, 1)
    assert run.description["plan"] == ["study bowl", "plan: budget 40"]
    assert run.description["out"] == str((tmp_path / "out").resolve())
    assert printed == ["  global model: 30 samples", "  refinement: 10 simulations"]
    assert [text for _, text in messages[run.id]] == printed
    journal.finish()
    journal.finish()  # idempotent
    (run,), _ = _read(path)
    assert run.outcome == "finished" and run.ended >= run.started
    # A second run of the same study is a second row; the store is still a store.
    RunJournal(path, problem.fingerprint(), "bowl", described).finish("stopped: broken simulator")
    runs, _ = _read(path)
    assert [r.outcome for r in runs] == ["finished", "stopped: broken simulator"]
    with SampleStore(path) as store:
        assert store.count() == 1


def test_several_objectives_are_described_in_order(tmp_path):
    problem = Bowl()
    problem.objectives = ("g", "f")
    assert describe_run(problem)["objectives"] == ["g", "f"]


def test_a_file_that_is_not_a_store_is_one_line(tmp_path):
    path = tmp_path / "notes.sqlite"
    path.write_text("not a database " * 100)
    with pytest.raises(InputError, match="not a usable sample store"):
        RunJournal(path, "fp", "bowl", {})
