"""Errors and warnings of the surrogate package.

Every error a caller can provoke with bad input (too few samples, NaN samples, a zero direction, line nodes that do
not admit a unisolvent blend, ...) is a :class:`SurrogateError` carrying a one-line message that names the offending
value and what was expected.  It derives from :class:`ValueError` so callers that only know the standard library can
still catch it; the package deliberately does not import ``sim`` to share a base class.
"""

from __future__ import annotations


class SurrogateError(ValueError):
    """Bad input to the surrogate mathematics; the message is one line meant for the user."""


class SurrogateWarning(UserWarning):
    """A result was produced but is questionable (e.g. an exponential fit with negative real nodes)."""
