"""Exceptions of mechopt that carry a one-line message meant for the user.

Every error a user can provoke with bad input derives from :class:`MechoptError`; the CLI prints its message on one
line and exits with a non-zero status instead of showing a traceback.
"""

from __future__ import annotations


class MechoptError(Exception):
    """Base class of the errors whose message is shown to the user as is."""


class InputError(MechoptError, ValueError):
    """A value given by the user is out of its domain (negative length, NaN, unknown name...)."""


class InfeasibleDesignError(MechoptError):
    """The design cannot move through the prescribed stroke (not assemblable or crank not monotonic)."""


class StudyError(MechoptError):
    """A study definition (TOML) is missing, malformed or incomplete."""


class BrokenSimulatorError(MechoptError):
    """The first simulations of a run all failed: the simulator itself, not the designs, is at fault."""
