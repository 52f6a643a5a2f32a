"""Progress lines when standard error is a file: one per tenth of the plan, and never a long silence (issue 52)."""

from __future__ import annotations

import io
import re
import subprocess
import sys
import time

from mechopt.runs.progress_log import ProgressLog, duration, wants_log_lines
from mechopt.runs.store import SampleRecord

LINE = re.compile(r"^progress: (\d+)/(\d+) simulations \(\d+ %\), best f (.+?), (\d+) failed, .* elapsed, .*$")


def record(i: int, value: float | None) -> SampleRecord:
    if value is None:
        return SampleRecord(design=(float(i),), fingerprint="fp", status="failed", error="boom", wall_time_s=0.01)
    return SampleRecord(design=(float(i),), fingerprint="fp", status="ok", outputs={"f": value}, wall_time_s=0.01)


def test_a_line_at_each_tenth_with_the_best_so_far_and_the_failures():
    stream = io.StringIO()
    log = ProgressLog(20, "f", stream=stream, interval_s=3600.0)
    try:
        for i in range(20):
            log.record(record(i, None if i % 5 == 0 else 100.0 - i))
    finally:
        log.close()
    lines = stream.getvalue().splitlines()
    assert len(lines) == 10
    parsed = [LINE.match(line).groups() for line in lines]
    assert [int(done) for done, *_ in parsed] == list(range(2, 21, 2))
    assert parsed[-1][2] == "81" and parsed[-1][3] == "4"  # best 100 - 19; designs 0, 5, 10, 15 failed
    assert lines[-1].endswith("no simulation left")


def test_a_trade_off_reports_its_front_over_the_designs_that_meet_the_limits():
    import numpy as np

    def score(r: SampleRecord):  # (f, g) minimised; a design meets the limit when g <= 1
        return np.array([r.outputs["f"], r.outputs["g"]]) if r.outputs["h"] <= 1.0 else None

    stream = io.StringIO()
    log = ProgressLog(4, ("f", "g"), stream=stream, interval_s=3600.0, score=score)
    points = [(0.0, 2.0, 5.0), (1.0, 1.0, 0.0), (2.0, 0.0, 0.0), (3.0, 3.0, 0.0)]  # the first breaks the limit
    try:
        for i, (f, g, h) in enumerate(points):
            log.record(SampleRecord(design=(float(i),), fingerprint="fp", status="ok",
                                    outputs={"f": f, "g": g, "h": h}, wall_time_s=0.01))
            if i == 0:
                assert "no design meeting the limits yet (f, g)" in log.line()
    finally:
        log.close()
    assert "front of 2 designs (f, g)" in stream.getvalue().splitlines()[-1]


def test_a_line_at_least_every_interval_while_nothing_arrives():
    stream = io.StringIO()
    log = ProgressLog(1000, "f", stream=stream, interval_s=0.2)
    log.record(record(0, 3.0))
    time.sleep(1.1)
    log.close()
    lines = stream.getvalue().splitlines()
    assert 4 <= len(lines) <= 6  # at 0.2, 0.4, ... 1.0 s
    assert all(line.startswith("progress: 1/1000 simulations") and "best f 3," in line for line in lines)
    count = len(lines)
    time.sleep(0.5)
    assert len(stream.getvalue().splitlines()) == count  # closed: silent


def test_durations_and_terminals():
    assert [duration(s) for s in (4.4, 200, 7500)] == ["4 s", "3 min 20 s", "2 h 05 min"]
    assert wants_log_lines(io.StringIO())


def test_a_study_with_stderr_in_a_file_writes_a_line_per_tenth(tmp_path):
    log = tmp_path / "stderr.txt"
    with open(log, "w") as err:
        argv = ["study", "branin", "--budget", "30", "--method", "auto", "--workers", "1", "--out", str(tmp_path / "o")]
        proc = subprocess.run([sys.executable, "-m", "mechopt.cli.main", *argv], stdout=subprocess.PIPE, stderr=err,
                              text=True, timeout=300)
    assert proc.returncode == 0
    lines = log.read_text().splitlines()
    progress = [LINE.match(line) for line in lines]
    assert len(lines) >= 10 and all(progress), lines
    done = [int(m.group(1)) for m in progress]
    assert done == sorted(done) and done[-1] == int(progress[-1].group(2)) == 30
