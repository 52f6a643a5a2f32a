"""The work loop of :func:`~mechopt.runs.sampling.sample_designs`, shared with the other runs on the same store.

A run claims a few designs at a time (as many as its executor has free slots) before evaluating them, with a lease
that a :class:`~mechopt.runs.claim_heartbeat.ClaimHeartbeat` renews; designs validly claimed by another run are not
evaluated but waited for, and taken over when their claim expires (their run died) or is released (it was
interrupted).  Each result is stored, in the calling process, as it arrives.  Claims are released when the loop ends,
however it ends.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Iterator
from typing import Any

from tqdm.auto import tqdm

from mechopt.errors import MechoptError
from mechopt.runs.claim_heartbeat import ClaimHeartbeat
from mechopt.runs.executors import SampleExecutor, make_executor
from mechopt.runs.store import SampleRecord, SampleStore, new_owner

__all__ = ["CooperativeEvaluation", "is_final"]

# Polling of designs another run is evaluating: first check soon (short evaluations), then back off.
_POLL_FIRST_S = 0.02
_POLL_MAX_S = 0.5


def is_final(record: SampleRecord, redo_failed_before: str | None) -> bool:
    """Whether a stored record settles its design for this call.

    Parameters
    ----------
    record : SampleRecord
        A stored record.
    redo_failed_before : str or None
        ISO timestamp of the call's start when it retries failures: a failure stored before it is still to be
        redone, one stored since is final.  None: every record is final.

    Returns
    -------
    bool
    """
    return not (redo_failed_before is not None and record.status == "failed" and record.timestamp < redo_failed_before)


class CooperativeEvaluation:
    """The designs of one call not yet settled: evaluated here under claims, or waited for from the runs holding them.

    Parameters
    ----------
    store : SampleStore
        Where results are looked up, claimed and written.
    fingerprint : str
        Key of the problem's rows in the store.
    found : dict
        Design key -> record of the designs already settled; every design settled by :meth:`run` is added.
    pending : dict
        Design key -> design (tuple of float, in the variables' units) of the designs to settle, in order of
        preference; :meth:`run` removes each design as it settles it.
    n_cached : int
        Designs found in the store at the start (shown on the progress bar).
    redo_failed_before : str or None
        See :func:`is_final`.
    lease_s : float
        Lease of this run's claims, s.
    on_record : callable, optional
        ``on_record(record)`` for each design settled by :meth:`run`, as it is settled; what it raises ends the run
        (the early stop of a broken simulator).

    Attributes
    ----------
    counts : dict
        Designs settled by :meth:`run`: ``"computed"`` here, ``"waited"`` for from another run, and of them the
        ``"failed"`` and ``"infeasible"`` ones.
    compute_time_s : float
        Sum of the evaluator wall times of the designs evaluated here, s.
    description : str
        Description of the executor used (empty when nothing was evaluated here).
    """

    def __init__(
        self,
        store: SampleStore,
        fingerprint: str,
        found: dict[str, SampleRecord],
        pending: dict[str, tuple[float, ...]],
        *,
        n_cached: int,
        redo_failed_before: str | None,
        lease_s: float,
        on_record: Callable[[SampleRecord], None] | None = None,
    ) -> None:
        self.store = store
        self.fingerprint = fingerprint
        self.found = found
        self.pending = pending
        self.n_cached = n_cached
        self.redo_failed_before = redo_failed_before
        self.lease_s = lease_s
        self.on_record = on_record
        self.owner = new_owner()
        self.counts = {"computed": 0, "waited": 0, "failed": 0, "infeasible": 0}
        self.compute_time_s = 0.0
        self.description = ""
        self._order = list(pending)
        self._cursor = 0  # _order[:_cursor] are all settled or submitted
        self._claimed = False
        self._heartbeat: ClaimHeartbeat | None = None
        self._own_executor: SampleExecutor | None = None
        self._bar: Any = None

    def run(
        self,
        task: Callable[[tuple[float, ...]], SampleRecord],
        executor: SampleExecutor | None,
        *,
        progress: bool,
        desc: str,
    ) -> None:
        """Settle every pending design, then stop the heartbeat, release the claims and close what was opened.

        Parameters
        ----------
        task : callable
            ``task(design) -> SampleRecord``, run by the executor.
        executor : SampleExecutor or None
            Where to evaluate; None: :func:`~mechopt.runs.executors.make_executor` with every core, created only
            if this run gets something to evaluate, and closed at the end.  A given executor is left open.
        progress : bool
            Show a tqdm bar (silent anyway when stderr is not a terminal).
        desc : str
            Label of the progress bar.
        """
        self._bar = tqdm(total=len(self.pending), desc=desc, unit="design", disable=None if progress else True,
                         dynamic_ncols=True)
        self._bar.set_postfix(cached=self.n_cached, refresh=False)
        try:
            self._settle_all(task, executor)
        except BaseException:
            self._finish(quiet=True)
            raise
        self._finish(quiet=False)

    def _settle_all(self, task: Callable[[tuple[float, ...]], SampleRecord], executor: SampleExecutor | None) -> None:
        ex = executor
        poll = _POLL_FIRST_S
        while self.pending:
            # Results of other runs (and of runs that finished meanwhile).
            for record in self.store.get_keys(self.pending, self.fingerprint).values():
                if is_final(record, self.redo_failed_before):
                    self._settle(record, waited=True)
            if not self.pending:
                break
            if ex is None:
                ex = self._own_executor = make_executor()
            limit = max(1, ex.max_in_flight)
            submitted: set[str] = set()
            first = self._claim(submitted, limit)
            if not first:
                # Everything left is being evaluated by other runs: wait for it, or for a claim to lapse.
                time.sleep(poll)
                poll = min(1.5 * poll, _POLL_MAX_S, self.lease_s / 4.0)
                continue
            poll = _POLL_FIRST_S
            if self._heartbeat is None:
                self._heartbeat = ClaimHeartbeat(self.store, self.owner, self.lease_s)
            self.description = ex.description
            for record in ex.map_unordered(task, self._feed(first, submitted, limit)):
                if not self.store.put(record):
                    # Another run stored this design meanwhile (it took over a claim of ours): its row rules.
                    record = self.store.get_keys([record.key], self.fingerprint).get(record.key) or record
                self.compute_time_s += record.wall_time_s or 0.0
                self._settle(record, waited=False)

    def _settle(self, record: SampleRecord, waited: bool) -> None:
        self.found[record.key] = record
        self.pending.pop(record.key, None)
        self.counts["waited" if waited else "computed"] += 1
        if not record.ok:
            self.counts[record.status] += 1
        shown = {k: v for k, v in self.counts.items() if v and k != "computed"}
        self._bar.set_postfix(cached=self.n_cached, **shown, refresh=False)
        self._bar.update(1)
        if self.on_record is not None:
            self.on_record(record)

    def _claim(self, submitted: set[str], limit: int) -> list[str]:
        """Claim up to ``limit`` pending designs not yet submitted, first in order of preference."""
        self._claimed = True
        order, pending = self._order, self.pending
        while self._cursor < len(order) and (order[self._cursor] not in pending or order[self._cursor] in submitted):
            self._cursor += 1
        # Lazy: without contention claim() reads only the first few candidates.
        candidates = (
            order[i] for i in range(self._cursor, len(order)) if order[i] in pending and order[i] not in submitted
        )
        return self.store.claim(self.fingerprint, candidates, self.owner, self.lease_s, limit=limit,
                                redo_failed_before=self.redo_failed_before)

    def _feed(self, first: list[str], submitted: set[str], limit: int) -> Iterator[tuple[float, ...]]:
        # Pulled by the executor one design per free slot: claim the next few only when the last are submitted,
        # so that at most about max_in_flight designs are claimed but not yet stored.
        queue = deque(first)
        while queue:
            key = queue.popleft()
            submitted.add(key)
            yield self.pending[key]
            if not queue:
                queue.extend(self._claim(submitted, limit))

    def _finish(self, quiet: bool) -> None:
        """Stop the heartbeat, release this run's claims, close an executor we created, close the bar.

        With ``quiet`` (an exception is on its way out) a failure to release is ignored: the claims then lapse after
        their lease, and the original error is the one to show.
        """
        try:
            if self._heartbeat is not None:
                self._heartbeat.stop()
            if self._claimed:
                try:
                    self.store.release_claims(self.owner)
                except MechoptError:
                    if not quiet:
                        raise
        finally:
            try:
                if self._own_executor is not None:
                    self._own_executor.close()
            finally:
                self._bar.close()
