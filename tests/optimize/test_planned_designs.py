"""The line plan printed before a run is the plan the run samples, found once per problem."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

import mechopt.optimize.sparse.stage as stage
from mechopt.optimize.sparse.options import SparseOptions
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.studies.catalogue import load_study


def test_a_plan_is_found_once_per_problem_and_a_changed_problem_gets_its_own(monkeypatch):
    problem = load_study("ventilator", {"engine": "analytic"}).problem
    options = SparseOptions.for_budget(60, problem.dim)
    calls = []
    plan_stage = stage.plan_stage
    monkeypatch.setattr(stage, "plan_stage", lambda *a, **k: calls.append(a[0].problem) or plan_stage(*a, **k))
    monkeypatch.setattr(stage, "_PLANS", {})

    def designs(p, opts=options):
        return stage.planned_designs(ModelSpace(p), opts, opts.n_lines, opts.samples_per_line)[2]

    first = designs(problem)
    again = designs(problem)  # another ModelSpace of the same problem: the run after its printed plan
    assert len(calls) == 1
    assert len(first) == len(again) and all(np.array_equal(a, b) for a, b in zip(first, again, strict=True))
    # A stricter toggle margin moves the feasible region's edge: a new problem object, a plan of its own.
    stricter = replace(problem, mechanism=replace(problem.mechanism, toggle_margin_deg=35.0))
    other = designs(stricter)
    assert len(calls) == 2 and calls[1] is stricter
    assert not np.array_equal(np.vstack(other), np.vstack(first))
    # Other options (another seed) are another plan too.
    designs(problem, options.replace(seed=options.seed + 1))
    assert len(calls) == 3
