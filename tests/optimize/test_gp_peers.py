"""Optuna's GPSampler and BoTorch's qLogNEI peers: each spends its whole budget, simulates only feasible designs in
the box, never returns a failed simulation, and says in one line which extra is missing.

Small budgets (a process is refitted at every step), BoTorch with a lighter acquisition search (2 restarts from 64
raw samples instead of 10 from 512: the loop is the same).  Skipped when PyTorch or BoTorch is not installed.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
from recorder import Recorder

from mechopt.optimize.baselines import CountedProblem, MissingLibraryError
from mechopt.optimize.baselines.library import GP_PEERS_HINT
from mechopt.optimize.methods import METHODS

pytest.importorskip("torch", reason="the GP peers need PyTorch (the gp-peers extra)")
pytest.importorskip("botorch", reason="the BoTorch peer needs BoTorch (the gp-peers extra)")

#: The constrained bowl of test_library_baselines.py: ``Σ w (x − c)²`` on [−2, 2]^3 under x1 + x2 + x3 <= 2.4 (active
#: at the minimum) and outside a ball of radius 0.8 around (−1, −1, 0).
BOX = np.array([[-2.0, 2.0]] * 3)
W, C = np.array([1.0, 2.0, 4.0]), np.array([1.2, 0.9, 1.1])
Q_FSTAR = (C.sum() - 2.4) ** 2 / np.sum(1.0 / W)  # the KKT minimum on the plane x1 + x2 + x3 = 2.4


class SimulationFailed(RuntimeError):
    pass


def quad(x: np.ndarray) -> float:
    return float(np.sum(W * (np.asarray(x) - C) ** 2))


def margins(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return np.stack([2.4 - x.sum(axis=-1), np.linalg.norm(x - [-1.0, -1.0, 0.0], axis=-1) - 0.8], axis=-1)


def make(budget: int) -> tuple[CountedProblem, Recorder]:
    rec = Recorder(quad, margins, BOX)
    return CountedProblem(rec, BOX, budget, margins, vectorized_constraints=True), rec


LIGHT = {"optuna_gp": {}, "botorch_qlognei": {"num_restarts": 2, "raw_samples": 64}}


def run(name: str, problem: CountedProblem, seed: int):
    return METHODS[name].function(problem, seed, **LIGHT[name])


@pytest.mark.parametrize("name", sorted(LIGHT))
def test_spends_its_whole_budget_in_the_box_and_only_on_feasible_designs(name):
    # QUAD: the minimum on the linear constraint, a spherical hole; 12 calls = the start-up designs and 2-4 steps.
    problem, rec = make(12)
    res = run(name, problem, 0)
    assert METHODS[name].spends_whole_budget
    assert res.nfev == rec.calls == problem.nfev == 12, res.message
    X = np.array(rec.xs)
    assert np.all((X >= BOX[:, 0]) & (X <= BOX[:, 1])) and all(rec.feasible)
    assert res.success and rec.is_feasible(res.x)
    assert res.fun == min(rec.values) == quad(res.x) >= Q_FSTAR - 1e-9


@pytest.mark.parametrize("name", sorted(LIGHT))
def test_a_box_off_the_origin_and_failed_simulations(name):
    # An unconstrained box far from the unit cube; the simulator fails where x1 > 4.5 (a tenth of the box).
    box = np.array([[2.0, 5.0], [-30.0, -10.0]])

    def fragile(x):
        if x[0] > 4.5:
            raise SimulationFailed
        return float((x[0] - 3.0) ** 2 + 0.01 * (x[1] + 20.0) ** 2)

    rec = Recorder(fragile, lambda x: np.zeros(0), box)
    problem = CountedProblem(rec, box, 13, failure_errors=(SimulationFailed,))
    res = run(name, problem, 1)
    assert res.nfev == rec.calls == 13, res.message
    X = np.array(rec.xs)
    assert np.all((X >= box[:, 0]) & (X <= box[:, 1]))
    assert res.success and res.x[0] <= 4.5 and np.isfinite(res.fun)


@pytest.mark.parametrize(("name", "module"), [("optuna_gp", "torch"), ("botorch_qlognei", "botorch")])
def test_a_missing_library_names_the_gp_peers_extra(name, module, monkeypatch):
    monkeypatch.setitem(sys.modules, module, None)
    problem, rec = make(10)
    with pytest.raises(MissingLibraryError) as info:
        run(name, problem, 0)
    assert "\n" not in str(info.value) and GP_PEERS_HINT in str(info.value) and rec.calls == 0
