"""The heartbeat of a live sampling run: a thread that keeps renewing the run's claims while evaluations go on."""

from __future__ import annotations

import threading

from mechopt.errors import MechoptError
from mechopt.runs.store import SampleStore

__all__ = ["ClaimHeartbeat"]


class ClaimHeartbeat:
    """Renews a run's claims every ``lease_s / 3`` from a thread with its own connection, while evaluations run.

    Parameters
    ----------
    store : SampleStore
        The run's store; the thread opens its own connection to the same file (a connection is not shared
        between threads).
    owner : str
        The run's owner id (:func:`~mechopt.runs.store.new_owner`).
    lease_s : float
        Lease of the claims, s; renewed three times per lease so that one missed beat does not let them lapse.
    """

    def __init__(self, store: SampleStore, owner: str, lease_s: float) -> None:
        self._args = (store.path, store.timeout, owner, lease_s)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="mechopt-claims-heartbeat", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        path, timeout, owner, lease_s = self._args
        try:
            with SampleStore(path, timeout=timeout) as store:
                while not self._stop.wait(lease_s / 3.0):
                    try:
                        store.renew_claims(owner, lease_s)
                    except MechoptError:
                        pass  # the next beat tries again; a lapse can only make another run duplicate work
        except MechoptError:
            pass

    def stop(self) -> None:
        """Stop renewing and wait for the thread to end (the claims keep their last lease)."""
        self._stop.set()
        self._thread.join()
