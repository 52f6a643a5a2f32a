"""A study re-run whose every simulation is in the store replays its method's answer instead of computing it again.

A method is deterministic: given the problem, its options, seed, starting designs and batch size, and the outputs of
the designs it simulated, it asks for the same designs and gives the same answer.  A re-run of a finished study
therefore spent minutes (the ventilator: the line model's search and the refinement's constraint margins) to find
what it had found.  After a run, :func:`save` keeps the method's answer in the output folder with the designs it
asked for and a digest of their stored records; :func:`replay` gives it back when the run's key is the same and
every one of those designs is still in the store with the same outputs, and registers them with the sampler as
reused, so counts, history and report are those of the run that computed it.  Anything else (another option,
another mechopt, a record changed, ``--retry-failed``) computes again.

The answer is kept as a pickle (``method_cache.pickle``): like any pickle, it can run code when loaded, so it is
read only from the output folder of the study being run, which the user chose (and which holds this study's
results: :mod:`mechopt.studies.output_folder`).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import pickle
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.runs.store import design_key

__all__ = ["CACHE_FILE", "code_digest", "replay", "run_key", "save"]

#: The file in a study's output folder.
CACHE_FILE = "method_cache.pickle"
_PACKAGE = Path(__file__).resolve().parents[1]


@functools.cache
def code_digest() -> str:
    """Digest of mechopt's source: an edited method computes again."""
    h = hashlib.sha256()
    for path in sorted(_PACKAGE.rglob("*.py")):
        if "tests" not in path.relative_to(_PACKAGE).parts[:1] and "benchmarks" not in path.parts:
            h.update(str(path.relative_to(_PACKAGE)).encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def run_key(problem: Any, method: str, options: Any, x0: np.ndarray | None, batch_size: int) -> str:
    """What decides the method's answer, besides the simulated outputs, as one digest."""
    parts = {"fingerprint": problem.fingerprint(), "method": method, "options": options.to_dict(),
             "x0": None if x0 is None else np.asarray(x0, dtype=float).tolist(), "batch": int(batch_size),
             "code": code_digest()}
    return hashlib.sha256(json.dumps(parts, sort_keys=True, default=str).encode()).hexdigest()


def _records_digest(store: Any, fingerprint: str, designs: list[tuple[float, ...]]) -> str | None:
    """Digest of the stored records of ``designs`` (status and outputs); None when one is missing."""
    found = store.get_many(designs, fingerprint)
    h = hashlib.sha256()
    for d in designs:
        record = found.get(design_key(d))
        if record is None:
            return None
        h.update(json.dumps([design_key(d), record.status, record.outputs], sort_keys=True, default=str).encode())
    return h.hexdigest()


def save(out: Path, key: str, sampler: Any, result: Any) -> None:
    """Keep the method's answer and the designs it asked for (nothing when the answer cannot be pickled)."""
    asked = list(sampler.asked.values())
    valued = [d for d, _ in sampler.history.values()]
    digest = _records_digest(sampler.store, sampler.fingerprint, asked)
    if digest is None:
        return
    try:
        blob = pickle.dumps({"key": key, "asked": asked, "valued": valued, "digest": digest, "result": result})
    except (pickle.PicklingError, TypeError, AttributeError):
        return
    with contextlib.suppress(OSError):
        (out / CACHE_FILE).write_bytes(blob)


def replay(out: Path, key: str, sampler: Any) -> Any | None:
    """The kept answer when ``key`` matches and every design it asked for is stored unchanged, else None.

    The designs are asked of the sampler again (all found in the store): it counts them as reused and its history
    is the computing run's.
    """
    path = out / CACHE_FILE
    if sampler.retry_failed or not path.is_file():
        return None
    try:
        blob = path.read_bytes()
        kept = pickle.loads(blob)
    except (OSError, pickle.UnpicklingError, EOFError, AttributeError, ImportError, TypeError, ValueError):
        return None
    if not isinstance(kept, dict) or kept.get("key") != key:
        return None
    if _records_digest(sampler.store, sampler.fingerprint, kept["asked"]) != kept["digest"]:
        return None
    if kept["asked"]:
        sampler.records(np.array(kept["asked"], dtype=float), desc="replay")
    if kept["valued"]:
        sampler(np.array(kept["valued"], dtype=float), desc="replay")
    return kept["result"]
