"""What a user's simulator returns, how its failures read, and the content hashes that key its samples.

Shared by the command and the Python-callable simulators: the outputs are one JSON-like object holding every declared
output as a finite number (extra keys are kept), or ``{"infeasible": "reason"}`` when the design cannot be simulated.
"""

from __future__ import annotations

import hashlib
import math
import os
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from mechopt.errors import InfeasibleDesignError, MechoptError

__all__ = ["INFEASIBLE_KEY", "SimulatorFailure", "checked_outputs", "file_digest", "resolve_entry", "text_digest"]

#: The key by which a simulator says a design cannot be simulated (the value is the reason).
INFEASIBLE_KEY = "infeasible"

# Hashing a large solver binary on every fingerprint would cost seconds; its digest is kept while it is unchanged.
_DIGESTS: dict[tuple[str, int, int], str] = {}


class SimulatorFailure(MechoptError):
    """A user's simulator did not deliver outputs for a design (recorded as a failed sample, the run goes on)."""


def file_digest(path: str | Path) -> str:
    """SHA-256 of a file's contents (hex), cached by path, size and modification time.

    Parameters
    ----------
    path : str or Path
        An existing file.

    Returns
    -------
    str
        64 hexadecimal digits.
    """
    path = Path(path).resolve()
    stat = path.stat()
    key = (str(path), stat.st_size, stat.st_mtime_ns)
    if key not in _DIGESTS:
        digest = hashlib.sha256()
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
        _DIGESTS[key] = digest.hexdigest()
    return _DIGESTS[key]


def text_digest(text: str) -> str:
    """SHA-256 (hex, 16 digits) of a string: how a secret such as a licence key enters a fingerprint unseen."""
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def checked_outputs(out: Any, names: Sequence[str], context: str = "") -> dict[str, Any]:
    """The outputs of one simulation, checked: every declared one a finite number.

    Parameters
    ----------
    out : object
        What the simulator returned (a parsed JSON object, or a Python function's return value).
    names : sequence of str
        The declared outputs (``[simulator] outputs``).
    context : str
        Appended to a failure's message (exit code, stderr), e.g. ``"; exit code 0; stderr: ..."``.

    Returns
    -------
    dict
        ``out`` as a plain dict, declared outputs converted to float.

    Raises
    ------
    InfeasibleDesignError
        ``out`` is ``{"infeasible": reason}``.
    SimulatorFailure
        ``out`` is not an object, or a declared output is missing, not a number or not finite (the message names it).
    """
    if not isinstance(out, Mapping):
        raise SimulatorFailure(f"returned {type(out).__name__}, expected an object with outputs {list(names)}{context}")
    if INFEASIBLE_KEY in out and out[INFEASIBLE_KEY] not in (None, False):
        reason = out[INFEASIBLE_KEY]
        raise InfeasibleDesignError(str(reason) if isinstance(reason, str) and reason else "infeasible design")
    result = dict(out)
    for name in names:
        if name not in out:
            raise SimulatorFailure(f"output {name!r} missing (got {sorted(map(str, out))}){context}")
        value = out[name]
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise SimulatorFailure(f"output {name!r} is not a number: {value!r:.60}{context}")
        if not math.isfinite(value):
            raise SimulatorFailure(f"output {name!r} is not finite: {value!r}{context}")
        result[name] = float(value)
    return result


def resolve_entry(entry: str, folder: str, python: str | None = None) -> str:
    """An argv entry as the simulator gets it.

    Parameters
    ----------
    entry : str
        As written in the study file.
    folder : str
        The study file's folder.
    python : str, optional
        What ``{python}`` stands for; default the interpreter running mechopt (in the worker that runs it).

    Returns
    -------
    str
        ``{python}`` and ``{study}`` substituted, and a relative path naming an existing file beside the study file
        made absolute (the process may run in another folder).
    """
    text = entry.replace("{python}", sys.executable if python is None else python).replace("{study}", folder)
    if text and not os.path.isabs(text) and os.path.isfile(os.path.join(folder, text)):
        return os.path.join(folder, text)
    return text
