"""Every method of the table proposes only allowed designs: on a problem with a continuous, a grid, an integer and a
catalogue variable, every design simulated (the simulator's calls and the store's rows) and the answer lie on the
variables' grids, integers and catalogue, and no design is simulated twice."""

from __future__ import annotations

import numpy as np
import pytest

import mechopt
from mechopt.optimize.baselines.library import MissingLibraryError
from mechopt.optimize.methods import METHODS
from mechopt.runs.store import SampleStore, design_key
from tests.optimize.mixed_problem import MixedBowl

#: Small budgets keep the model-refitting baselines (bayesian, smt_ego) to seconds.
BUDGET = 10


def _budget(name: str) -> int:
    return max(BUDGET, METHODS[name].min_budget(4, BUDGET, None)[0], 3 * BUDGET if METHODS[name].line_model else 0)


@pytest.mark.parametrize("name", list(METHODS))
def test_every_design_simulated_and_returned_is_allowed(name, tmp_path):
    problem = MixedBowl()
    path = tmp_path / "samples.sqlite"
    budget = _budget(name)
    try:
        res = mechopt.minimize(problem, budget=budget, method=name, seed=0, store=path)
    except MissingLibraryError as exc:
        pytest.skip(f"optional library absent: {exc}")
    keys = [design_key(c) for c in problem.calls]
    assert problem.calls and len(keys) == len(set(keys)), "a design was simulated twice"
    assert problem.on_grid(np.array(problem.calls)).all()
    store = SampleStore(path)
    try:
        stored = np.array([r.design for r in store.records(problem.fingerprint())])
    finally:
        store.close()
    assert stored.shape[0] == len(keys) and problem.on_grid(stored).all()
    assert res.success and problem.on_grid(res.x)[0] and problem.feasible(res.x)[0]
    assert len(keys) <= budget
    # The answer is a design simulated, with its value.
    assert design_key(tuple(res.x)) in set(keys)
    assert res.fun == pytest.approx(problem.evaluate(res.x)["f"], rel=1e-12)
