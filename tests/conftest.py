"""Shared fixtures: the ventilator study is reconstructed once per test session."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture(scope="session")
def ventilator():
    from mechopt.studies.definition import load_study

    return load_study("ventilator", {"engine": "pymunk"})


@pytest.fixture(scope="session")
def mechanism(ventilator):
    return ventilator.problem.mechanism
