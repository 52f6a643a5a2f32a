"""Stop a run whose simulator is broken from the start, before it spends its budget.

A simulator that fails on every design (a missing licence, a wrong command, an evaluator that returns NaN) would
otherwise spend the whole budget before the run says so: hours with a CAD simulator.  :class:`EarlyStop` watches
the first ``k`` designs a run settles; when all of them failed, it raises :class:`BrokenSimulatorError` with the
first failure's reason.  One success (or one infeasible design, a legitimate answer) disarms it: failures later in a
run stay what they were, a hidden constraint the methods learn and avoid.
"""

from __future__ import annotations

from mechopt.errors import BrokenSimulatorError, InputError
from mechopt.runs.store import SampleRecord

__all__ = ["DEFAULT_STOP_AFTER_FAILURES", "BrokenSimulatorError", "EarlyStop", "check_stop_after_failures"]

#: Failed simulations in a row, from a run's first, that stop it.
DEFAULT_STOP_AFTER_FAILURES = 5


def check_stop_after_failures(value: object) -> int:
    """The number of first failures that stop a run (0 or None: never).

    Parameters
    ----------
    value : int or None
        ``stop_after_failures`` as given.

    Returns
    -------
    int
        A non-negative count (0 turns the early stop off).

    Raises
    ------
    InputError
        If ``value`` is not None or a non-negative integer.
    """
    if value is None:
        return 0
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise InputError(f"stop_after_failures = {value!r}: expected a non-negative integer (0: never stop early)")
    return value


class EarlyStop:
    """Raise :class:`BrokenSimulatorError` once the first ``k`` designs of a run have all failed.

    Parameters
    ----------
    k : int
        How many first failures in a row stop the run (0: never).
    retry_hint : str, optional
        How to simulate the recorded failures again once the simulator is fixed (ends the error's line).
    """

    def __init__(self, k: int, retry_hint: str = "retry_failed=True simulates them again") -> None:
        self.k = check_stop_after_failures(k)
        self.retry_hint = retry_hint
        self.seen = 0
        self.first_error: str | None = None
        self.armed = self.k > 0
        self.error: BrokenSimulatorError | None = None

    def record(self, record: SampleRecord, cached: bool = False) -> None:
        """Count one design the run settled (simulated, waited for, or found in the store).

        Raises
        ------
        BrokenSimulatorError
            When this is the ``k``-th design of the run and every one so far failed, and at every design after
            that (a method that caught the first one does not go on).
        """
        if self.error is not None:
            raise self.error
        if not self.armed:
            return
        if record.status != "failed":
            self.armed = False
            return
        self.seen += 1
        if self.first_error is None:
            self.first_error = record.error or "failed"
        if self.seen >= self.k:
            self.armed = False
            self.error = BrokenSimulatorError(
                f"the first {self.k} simulations all failed, the first with: {self.first_error}; the run stopped "
                f"before spending more of its budget (stop_after_failures = {self.k}; 0 never stops early); once "
                f"the simulator is fixed, {self.retry_hint}")
            raise self.error
