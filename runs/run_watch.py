"""What watches a run as its simulations arrive: the early stop of a broken simulator and the progress lines of a log.

Both see every distinct design of the run once, as it is settled (a sampler's ``watchers``; see
:class:`~mechopt.optimize.sparse.sampler.Sampler`), and know nothing of the method that asked for it.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any

import numpy as np

from mechopt.runs.early_stop import EarlyStop
from mechopt.runs.progress_log import ProgressLog, wants_log_lines

__all__ = ["watch_run"]


def _trade_off_score(problem: Any) -> Any:
    """A trade-off's minimised objectives of a record that meets every limit (None otherwise); None for a problem
    of one objective and no limits on simulated outputs."""
    if not getattr(problem, "trade_off", False):
        return None
    spec, limits = problem.objective_spec, problem.limit_spec

    def score(record: Any) -> np.ndarray | None:
        f = spec.values(record.outputs)
        if not np.all(np.isfinite(f)):
            return None
        if limits.m and not limits.met(limits.values(record.outputs)[None, :])[0]:
            return None
        return f

    return score


@contextlib.contextmanager
def watch_run(sampler: Any, planned: int, *, progress: bool, stop_after_failures: int,
              retry_hint: str = "retry_failed=True simulates them again") -> Iterator[ProgressLog | None]:
    """Attach the run's watchers to ``sampler`` for the duration of the block.

    Parameters
    ----------
    sampler : Sampler
        The run's door to the simulator (its ``watchers`` list and ``problem.objective`` are used).
    planned : int
        Simulations the run plans (the denominator of the progress lines).
    progress : bool
        Whether the run shows progress: tqdm bars on a terminal, and when standard error is not a terminal
        (a log file, a pipe) one line at each tenth of ``planned`` and at least every 30 s.
    stop_after_failures : int
        Stop the run when its first this-many designs all failed (0: never).
    retry_hint : str, optional
        Ends the early stop's line: how to simulate the failures again once the simulator is fixed.

    Yields
    ------
    ProgressLog or None
        The progress log when lines are written, else None.
    """
    watchers: list[Any] = [EarlyStop(stop_after_failures, retry_hint)] if stop_after_failures else []
    problem = sampler.problem
    log = ProgressLog(planned, problem.objective, score=_trade_off_score(problem)) \
        if progress and wants_log_lines() else None
    if log is not None:
        watchers.append(log)
    sampler.watchers.extend(watchers)
    try:
        if log is not None:
            log.write()
        yield log
        if log is not None:
            log.write(unless_written=True)
    finally:
        if log is not None:
            log.close()
        for watcher in watchers:
            sampler.watchers.remove(watcher)
