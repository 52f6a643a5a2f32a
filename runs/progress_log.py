"""Progress lines for a run whose standard error is a log file or a pipe (a cluster job, ``nohup``).

On a terminal the run shows tqdm bars; written to a file those stay silent, and a run of hours would print nothing
between its plan and its end.  :class:`ProgressLog` writes one line at every tenth of the planned simulations and
at least every ``interval_s`` seconds (a background thread keeps that promise while a long simulation or the
method's own computing runs): simulations done / planned, the best objective so far, failures, elapsed and
estimated time left.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from collections.abc import Callable
from typing import TextIO

import moocore
import numpy as np

from mechopt.runs.store import SampleRecord

__all__ = ["ProgressLog", "duration", "wants_log_lines"]


def wants_log_lines(stream: TextIO | None = None) -> bool:
    """Whether progress goes to log lines: the stream (default ``sys.stderr``) is not a terminal."""
    stream = sys.stderr if stream is None else stream
    try:
        return not stream.isatty()
    except (AttributeError, ValueError):  # a closed or odd stream: no terminal there
        return True


def duration(seconds: float) -> str:
    """``"42 s"``, ``"3 min 20 s"``, ``"2 h 05 min"`` for a duration in s."""
    s = max(0, int(round(seconds)))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {(s % 3600) // 60:02d} min"


class ProgressLog:
    """Log lines on a run's progress, one per tenth of ``planned`` and at least every ``interval_s`` seconds.

    Parameters
    ----------
    planned : int
        Simulations the run plans (its budget, plus validation where there is one).
    objective : str or tuple of str
        Name of the output minimised (its best value is reported), or the objectives of a trade-off.
    stream : file, optional
        Where lines go (default ``sys.stderr``).
    interval_s : float, optional
        Longest silence, s (default 30).
    label : str, optional
        Prefix of every line.
    score : callable, optional
        ``score(record) -> (k,) ndarray or None``: a trade-off's minimised objectives of a design that meets every
        limit (None otherwise).  Given, the line reports the best of one objective, or the size of the front of
        several, over those designs only.
    """

    def __init__(self, planned: int, objective: str | tuple[str, ...], stream: TextIO | None = None,
                 interval_s: float = 30.0, label: str = "progress",
                 score: Callable[[SampleRecord], np.ndarray | None] | None = None) -> None:
        self.planned = max(1, int(planned))
        self.objective = objective if isinstance(objective, str) else ", ".join(objective)
        self.score = score
        self._points: list[np.ndarray] = []
        self.stream = stream
        self.interval_s = float(interval_s)
        self.label = label
        self.done = self.new = self.failed = 0
        self.best = math.inf
        self._tenth = 0
        self._written = -1  # designs done at the last line
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._start = self._last = time.monotonic()
        self._first_new: float | None = None
        self._thread = threading.Thread(target=self._tick, name="mechopt-progress-log", daemon=True)
        self._thread.start()

    def record(self, record: SampleRecord, cached: bool = False) -> None:
        """Count one design the run settled; write a line when it completes a tenth of the plan."""
        with self._lock:
            now = time.monotonic()
            self.done += 1
            if not cached:
                self.new += 1
                if self._first_new is None:
                    self._first_new = now - (record.wall_time_s or 0.0)
            if record.status == "failed":
                self.failed += 1
            elif record.ok and self.score is not None:
                point = self.score(record)
                if point is not None:
                    self._points.append(point)
                    self.best = min(self.best, float(point[0]))
            elif record.ok:
                value = record.value(self.objective)
                if math.isfinite(value):
                    self.best = min(self.best, value)
            tenth = min(10, 10 * self.done // self.planned)
        if tenth > self._tenth:
            self._tenth = tenth
            self.write()

    def line(self) -> str:
        """The progress line as of now."""
        now = time.monotonic()
        best = f"best {self.objective} " + (f"{self.best:.6g}" if math.isfinite(self.best) else "none yet")
        if self.score is not None and self._points and self._points[0].size > 1:
            front = int(np.sum(moocore.is_nondominated(np.array(self._points))))
            best = f"front of {front} designs ({self.objective})"
        elif self.score is not None and not self._points:
            best = f"no design meeting the limits yet ({self.objective})"
        left = max(0, self.planned - self.done)
        if left == 0:
            eta = "no simulation left"
        elif self.new and self._first_new is not None:
            eta = f"about {duration((now - self._first_new) / self.new * left)} left"
        else:
            eta = "time left not known yet"
        return (f"{self.label}: {self.done}/{self.planned} simulations ({100 * self.done / self.planned:.0f} %), "
                f"{best}, {self.failed} failed, {duration(now - self._start)} elapsed, {eta}")

    def write(self, unless_written: bool = False) -> None:
        """Write the progress line now (with ``unless_written``, only if a design arrived since the last line)."""
        with self._lock:
            if unless_written and self._written == self.done:
                return
            self._written = self.done
            stream = sys.stderr if self.stream is None else self.stream
            print(self.line(), file=stream, flush=True)
            self._last = time.monotonic()

    def close(self) -> None:
        """Stop the background thread (idempotent)."""
        self._stop.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join()

    def _tick(self) -> None:
        while not self._stop.wait(max(0.05, self._last + self.interval_s - time.monotonic())):
            if time.monotonic() - self._last >= self.interval_s:
                self.write()
