"""Whose results an output folder holds, and where a sample store may be made: checked before any simulation.

A study writes ``result.json``, ``report.md``, ``model.json``, ``front.csv`` and ``figures/*.png`` into its output
folder.  Pointed at the folder of another study (or of the same study on another problem: another engine, other
settings), it would overwrite that run's report and leave that run's other figures mixed with its own.  So a folder
whose ``result.json`` names another study or problem is refused, unless the user forces it; then the earlier run's
outputs are removed first (its sample store is kept: stores hold every problem's rows apart).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from mechopt.errors import InputError

__all__ = ["OUTPUT_FILES", "check_output_owner"]

#: What a study run writes into its output folder (``figures/*.png`` besides).
OUTPUT_FILES = ("result.json", "report.md", "model.json", "front.csv", "method_cache.pickle")


def _owner(result: Path) -> tuple[str, str] | None:
    """(study, problem fingerprint) of a ``result.json``; None when it is not a readable study result."""
    try:
        data = json.loads(result.read_text())
        return str(data["study"]), str(data["problem"]["fingerprint"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def check_output_owner(out: str | os.PathLike, study: str, fingerprint: str, force: bool = False) -> None:
    """Refuse an output folder that holds another study's or another problem's results (unless ``force``).

    Parameters
    ----------
    out : path
        The output folder (it may not exist yet).
    study : str
        Name of the study about to run.
    fingerprint : str
        Fingerprint of its problem.
    force : bool, optional
        Replace the other run's outputs instead: its ``result.json``, ``report.md``, ``model.json``, ``front.csv``
        and ``figures/*.png`` are removed (its sample store is kept).

    Raises
    ------
    InputError
        One line naming the folder and the study whose results it holds.
    """
    out = Path(out)
    result = out / "result.json"
    if not result.is_file():
        return
    owner = _owner(result)
    if owner == (study, fingerprint):
        return  # a re-run of the same study: its outputs are brought up to date
    if not force:
        held = ("a result.json that is not a mechopt study's" if owner is None else
                f"the results of study {owner[0]!r}" if owner[0] != study else
                f"the results of study {study!r} on another problem (fingerprint {owner[1][:12]}, now "
                f"{fingerprint[:12]}: another engine or other settings)")
        raise InputError(f"--out {out} holds {held}; nothing was overwritten: choose another folder, or --force to "
                         "replace them")
    for name in OUTPUT_FILES:
        (out / name).unlink(missing_ok=True)
    for figure in (out / "figures").glob("*.png"):
        figure.unlink()
