"""Simulate one ventilator design, as an external program would for mechopt: design JSON in, outputs JSON out.

A stand-in for a CAD batch run: mechopt starts this script once per design (``[simulator] command`` in
``study.toml``).  It reads ``{"oa": 53.0, "ab": 65.0, "bc": 282.0, "units": {"oa": "mm", ...}}`` from stdin (or
``design.json`` in the current folder with ``--files``), simulates the inhale stroke with mechopt's Exudyn (or pymunk)
engine and prints ``{"t_rms": ..., "t_max": ...}`` in N·m (or writes ``outputs.json``).  A design that cannot be
driven through the stroke is answered with ``{"infeasible": "reason"}``; anything else that goes wrong ends the
script with a non-zero exit code and a message on stderr, which mechopt records as a failed design.

Reconstructing the ventilator from its load table takes seconds, longer than one simulation, so the reconstructed
problem is kept in the user's cache folder, keyed by the hash of the files it was built from; a real CAD wrapper has
the same concern (open the model once per batch, not once per design, when the tool allows it).

Run it by hand::

    echo '{"oa": 53.0, "ab": 65.0, "bc": 282.0, "units": {"oa": "mm", "ab": "mm", "bc": "mm"}}' \\
        | python simulate_ventilator.py --engine exudyn
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import pickle
import sys
import tempfile
from pathlib import Path

import numpy as np

import mechopt
from mechopt.errors import InfeasibleDesignError
from mechopt.studies.catalogue import STUDIES_DIR

NAMES = ("oa", "ab", "bc")  # |OA|, |AB|, |BC| in mm


def _cache_file(engine: str) -> Path:
    """Where the reconstructed problem is kept: named by the hash of every file that shapes it."""
    import mechopt.sim.four_bar as fourbar

    digest = hashlib.sha256(engine.encode())
    shipped = STUDIES_DIR / "ventilator"
    sources = [shipped / "study.toml", shipped / "original_design_load_inertia.csv",
               *sorted(Path(fourbar.__file__).parent.glob("*.py"))]
    for path in sources:
        digest.update(path.read_bytes())
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "mechopt" / "ventilator_command" / f"problem-{digest.hexdigest()[:16]}.pickle"


def load_problem(engine: str):
    """The ventilator's design problem with ``engine``, from the cache or reconstructed (then cached)."""
    cache = _cache_file(engine)
    if cache.is_file():
        try:
            with open(cache, "rb") as fh:
                return pickle.load(fh)
        except (OSError, pickle.UnpicklingError, EOFError, AttributeError):
            pass  # damaged or from another version: rebuild it
    problem = mechopt.load_study("ventilator", {"engine": engine}).problem
    try:
        cache.parent.mkdir(parents=True, exist_ok=True)
        # Written aside and renamed: concurrent designs never read a half-written cache.
        with tempfile.NamedTemporaryFile(dir=cache.parent, delete=False) as fh:
            pickle.dump(problem, fh)
        os.replace(fh.name, cache)
    except OSError:
        pass  # a read-only cache folder only costs time
    return problem


def read_design(payload: dict) -> np.ndarray:
    """The design (mm) from the JSON mechopt sent; exits with a message if a length is missing or not in mm."""
    units = payload.get("units", {})
    for name in NAMES:
        if name not in payload:
            sys.exit(f"design has no {name!r}: {payload}")
        if units.get(name, "mm") != "mm":
            sys.exit(f"{name} is in {units[name]!r}; this wrapper expects mm")
    return np.array([float(payload[name]) for name in NAMES])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="exudyn", choices=("exudyn", "pymunk", "analytic"))
    parser.add_argument("--files", action="store_true", help="read design.json, write outputs.json (current folder)")
    args = parser.parse_args()
    payload = json.loads(Path("design.json").read_text() if args.files else sys.stdin.read())
    x = read_design(payload)
    problem = load_problem(args.engine)
    try:
        result = problem.evaluate(x)
        outputs = {"t_rms": result["t_rms"], "t_max": result["t_max"], "dt": result["dt"], "engine": args.engine}
    except InfeasibleDesignError as exc:
        outputs = {"infeasible": str(exc)}
    text = json.dumps(outputs)
    if args.files:
        Path("outputs.json").write_text(text)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
