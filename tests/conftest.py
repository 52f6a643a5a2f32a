"""Shared fixtures: the ventilator study is reconstructed once per test session."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")
# Helper modules of the tests (toy problems, a call recorder) import by name under --import-mode=importlib.
_HELPERS = str(Path(__file__).resolve().parent / "helpers")
if _HELPERS not in sys.path:
    sys.path.insert(0, _HELPERS)


@pytest.fixture(scope="session")
def ventilator():
    from mechopt.studies.catalogue import load_study

    return load_study("ventilator", {"engine": "pymunk"})


@pytest.fixture(scope="session")
def mechanism(ventilator):
    return ventilator.problem.mechanism
