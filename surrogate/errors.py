"""Errors and warnings of the surrogate package.

Every error a caller can provoke with bad input (too few samples, NaN samples, a zero direction, line nodes that do
not admit a unisolvent blend, ...) is a :class:`SurrogateError` carrying a one-line message that names the offending
value and what was expected.  It belongs to mechopt's one error family (:class:`mechopt.errors.MechoptError`, a module
of messages only, no physics) and derives from :class:`ValueError` so callers that only know the standard library can
still catch it.
"""

from __future__ import annotations

from mechopt.errors import MechoptError


class SurrogateError(MechoptError, ValueError):
    """Bad input to the surrogate mathematics; the message is one line meant for the user."""


class SurrogateWarning(UserWarning):
    """A result was produced but is questionable (e.g. an exponential fit with negative real nodes)."""
