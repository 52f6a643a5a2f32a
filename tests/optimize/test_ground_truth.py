"""The ground truth of the ventilator study: feasible, confirmed by pymunk, not beaten by a finer grid."""

import json

import numpy as np
import pytest

from mechopt.optimize.ground_truth import compute_ground_truth, load_or_compute
from mechopt.sim.four_bar.analytic import analytic_batch
from mechopt.sim.four_bar.feasibility import check_feasibility
from mechopt.sim.four_bar.pymunk_engine import simulate_pymunk


@pytest.fixture(scope="module")
def truth(ventilator):
    return compute_ground_truth(ventilator.problem, 2.0)


def test_optimum_is_feasible_and_confirmed_by_pymunk(ventilator, truth):
    x = np.array(truth.x)
    assert check_feasibility(x, ventilator.problem.mechanism).feasible[0]
    assert np.all((x >= ventilator.problem.bounds[:, 0]) & (x <= ventilator.problem.bounds[:, 1]))
    assert truth.fun <= truth.grid_fun
    assert simulate_pymunk(x, ventilator.problem.mechanism).t_rms == pytest.approx(truth.fun, rel=5e-3)


def test_finer_grid_around_it_finds_nothing_better(ventilator, truth):
    x = np.array(truth.x)
    axes = [np.linspace(c - 1.0, c + 1.0, 41) for c in x]  # 0.05 mm spacing, ±1 mm
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    inside = np.all((mesh >= ventilator.problem.bounds[:, 0]) & (mesh <= ventilator.problem.bounds[:, 1]), axis=1)
    mesh = mesh[inside]
    mesh = mesh[check_feasibility(mesh, ventilator.problem.mechanism).feasible]
    t_rms, _ = analytic_batch(mesh, ventilator.problem.mechanism, check=False)
    assert np.nanmin(t_rms) >= truth.fun * (1 - 1e-6)


def test_cache_round_trip(ventilator, truth, tmp_path):
    cache = tmp_path / "truth.json"
    cache.write_text(json.dumps({"key": "stale"}))
    first = load_or_compute(ventilator.problem, cache, 2.0)
    assert first.x == pytest.approx(truth.x)
    second = load_or_compute(ventilator.problem, cache, 2.0)  # read back, not recomputed
    assert second.wall_time_s == first.wall_time_s
