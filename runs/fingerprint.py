"""Fingerprints: one hash for every setting that changes a simulated output.

A stored sample is reused only under the same fingerprint, so a fingerprint must change whenever any output could:
the whole load table, not a summary of it; every feasibility setting whose verdict is stored; the engine and its
version.  Settings are written as canonical JSON (sorted keys, no spaces, integral floats as integers, tuples as
lists, numpy values as Python values) and hashed with SHA-256, so that the same settings always give the same hash
whatever the key order or the spelling ``20`` / ``20.0``.
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Any

from mechopt.errors import InputError

__all__ = ["canonical", "fingerprint"]


def canonical(value: Any) -> Any:
    """Plain JSON value with one spelling per meaning (20 and 20.0 alike, tuples as lists, numpy as Python).

    Parameters
    ----------
    value : JSON-like
        Numbers, strings, booleans, None, lists, tuples, dicts with string keys, paths, numpy values.

    Returns
    -------
    JSON-like
        The same value in canonical form.

    Raises
    ------
    InputError
        If a number is not finite or a value is not JSON-like.
    """
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise InputError(f"settings must be finite numbers, got {value!r}")
        # A TOML "20" and "20.0" mean the same setting; hash them alike (exactly representable integers only).
        if value.is_integer() and abs(value) < 2.0**53:
            return int(value)
        return value
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise InputError(f"settings keys must be strings, got {k!r}")
            out[k] = canonical(v)
        return out
    if isinstance(value, list | tuple):
        return [canonical(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "tolist"):  # numpy scalars and arrays, without importing numpy here
        return canonical(value.tolist())
    raise InputError(f"settings must be JSON-like (numbers, strings, lists, dicts), got {type(value).__name__}")


def fingerprint(settings: dict[str, Any]) -> str:
    """SHA-256 of the canonical JSON of ``settings``.

    Parameters
    ----------
    settings : dict
        JSON-like mapping of everything that changes a simulated output.  Keep out of it what does not (number of
        workers, output paths, sampling relaxations).

    Returns
    -------
    str
        64 hexadecimal characters.

    Raises
    ------
    InputError
        If ``settings`` is not a dict, or a value is not finite or not JSON-like.
    """
    if not isinstance(settings, dict):
        raise InputError(f"settings must be a dict, got {type(settings).__name__}")
    text = json.dumps(canonical(settings), sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()
