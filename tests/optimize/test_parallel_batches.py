"""Issue 28: every phase of the mechopt methods proposes as many designs at once as there are workers.

A real Dask ``LocalCluster`` runs a real subprocess simulator (an external-command study): the designs go out in
batches (fewer rounds than simulations), and the results equal those of the same batch size in-process (the method
depends on the batch size and the simulated values, never on the order in which the workers finish), and with one
worker those of one at a time.
"""

from __future__ import annotations

import numpy as np
import pytest

from mechopt import minimize
from mechopt.optimize.minimize import _options, run_method
from mechopt.optimize.sparse.model_exploration import explore
from mechopt.optimize.sparse.refine import refine_locally
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.optimize.sparse.stage import build_stage
from mechopt.optimize.sparse.trust_region import trust_region_steps
from mechopt.runs.executors import InProcessExecutor
from mechopt.runs.store import SampleStore
from mechopt.studies.benchmark_functions import Branin
from mechopt.studies.catalogue import load_study

SIM = """\
import json, math, sys
d = json.load(sys.stdin)
x, y = d["x"], d["y"]
print(json.dumps({"f": (x - 0.3) ** 2 + 2 * (y - 0.6) ** 2 + 0.1 * math.sin(5 * x) * math.cos(4 * y)}))
"""

STUDY = """\
name = "parallel-ext"
kind = "external"
[variables]
x = [0.0, 1.0]
y = [0.0, 1.0]
[simulator]
command = ["{python}", "-S", "sim.py"]
outputs = ["f"]
timeout_s = 60
"""


class BatchOf(InProcessExecutor):
    """In-process, one design after the other, announcing ``workers`` so that the method proposes that many."""

    def __init__(self, workers: int) -> None:
        super().__init__()
        self.workers = workers


@pytest.fixture(scope="module")
def command_problem(tmp_path_factory):
    folder = tmp_path_factory.mktemp("parallel")
    (folder / "sim.py").write_text(SIM)
    (folder / "study.toml").write_text(STUDY)
    return load_study(folder / "study.toml").problem


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=4, processes=False,
                                  dashboard_address=None) as local:
        yield local


def _in_process(problem, method: str, budget: int, workers: int, tmp_path):
    with SampleStore(tmp_path / f"{method}-{workers}.sqlite") as store:
        sampler = Sampler(problem, store, BatchOf(workers), progress=False)
        res = run_method(problem, method, _options(problem, None, budget, 0), sampler, lambda _line: None)
        return res, sampler


@pytest.mark.parametrize("method", ["sparse", "sparse-global", "auto"])
def test_a_dask_cluster_gets_batches_and_the_answer_of_the_same_batch_in_process(command_problem, cluster, method,
                                                                                 tmp_path):
    res = minimize(command_problem, budget=30, method=method, seed=0, workers=None, scheduler=cluster)
    assert res.batch_size == 4 and "Dask" in res.sampling["executor"]
    assert res.nfev == 30 and res.rounds < res.nfev / 2  # batches, not one simulation at a time
    assert 0.0 <= res.idle_share <= 1.0 and res.waiting_s > 0 and res.method_s > 0
    same, _ = _in_process(command_problem, method, 30, 4, tmp_path)
    np.testing.assert_array_equal(res.x, same.x)
    assert res.fun == same.fun


def test_one_dask_worker_is_one_at_a_time_as_in_process(command_problem, cluster, tmp_path):
    res = minimize(command_problem, budget=30, method="sparse-global", seed=0, workers=1, scheduler=cluster)
    alone = minimize(command_problem, budget=30, method="sparse-global", seed=0, workers=1)
    assert res.batch_size == alone.batch_size == 1
    np.testing.assert_array_equal(res.x, alone.x)
    assert res.fun == alone.fun and res.rounds == alone.rounds


def test_the_local_search_sends_each_design_with_its_gradient_and_finds_the_same_minimum(tmp_path):
    problem = Branin()
    space = ModelSpace(problem)
    found = {}
    for workers in (1, 4):
        with SampleStore(tmp_path / f"{workers}.sqlite") as store:
            sampler = Sampler(problem, store, BatchOf(workers), progress=False)
            opts = _options(problem, None, 60, 0)
            stage = build_stage("global", space, opts, sampler, opts.n_lines, opts.samples_per_line,
                                opts.search_points, max_samples=opts.line_cap())
            rounds = sampler.rounds
            refined = refine_locally(space, sampler, np.array([2.0, 4.0]), 30, stage, 1e-3)
            found[workers] = (refined.candidate, refined.simulated, refined.n_samples, sampler.rounds - rounds)
    (x1, f1, n1, r1), (x4, f4, n4, r4) = found[1], found[4]
    # The same search: a new design goes out with the d = 2 of its gradient, one round instead of three (a design
    # the line search rejects wastes its two, so the budget may end a little earlier).
    assert n1 == r1 == 26 and n4 <= 30 and r4 <= r1 / 2
    np.testing.assert_allclose(x4, x1, atol=1e-9)
    assert f4 == f1 and f1 < Branin.f_min + 1e-3


def _bowl(Z):
    Z = np.atleast_2d(Z)
    return (Z[:, 0] - 0.3) ** 2 + 2 * (Z[:, 1] - 0.6) ** 2


def test_batched_exploration_takes_its_steps_in_rounds_and_keeps_its_distances():
    rng = np.random.default_rng(5)
    Z0 = rng.random((6, 2))
    rounds = []

    def simulate_batch(Z):
        rounds.append(len(Z))
        return _bowl(Z)

    Z, q = explore(lambda z: float(_bowl(z)[0]), Z0, _bowl(Z0), None,
                   lambda U: np.ones(len(np.atleast_2d(U)), bool), 24, seed=1, cycle=(0.2, 0.0), batch=4,
                   simulate_batch=simulate_batch)
    assert sum(rounds) == 24 and Z.shape == (30, 2) and max(rounds) == 4 and len(rounds) == 6
    assert len({tuple(z) for z in Z}) == 30  # no design twice, lies and all
    assert np.linalg.norm(Z[np.argmin(q)] - [0.3, 0.6]) < 2e-2


def test_batched_trust_region_steps_reach_the_minimum_in_fewer_rounds():
    def truth(X):
        X = np.atleast_2d(X)
        return 1.0 + 4 * (X[:, 0] - 0.3) ** 2 + 9 * (X[:, 1] - 0.6) ** 2 + 3 * (X[:, 0] - 0.3) * (X[:, 1] - 0.6)

    def biased(X):
        return truth(np.atleast_2d(X) - 0.2) + 0.3

    rng = np.random.default_rng(0)
    X = rng.random((10, 2))
    box = np.array([[0.0, 1.0], [0.0, 1.0]])
    rounds = []

    def simulate_batch(Xb):
        rounds.append(len(Xb))
        return truth(Xb)

    res = trust_region_steps(biased, lambda x: float(truth(x)[0]), lambda Xc: np.ones(len(np.atleast_2d(Xc)), bool),
                             box, X, truth(X), 24, seed=0, batch=4, simulate_batch=simulate_batch)
    assert res.n_steps == sum(rounds) <= 24 and max(rounds) <= 4 and len(rounds) < res.n_steps
    assert res.value - 1.0 < 1e-3


def test_the_sampler_counts_rounds_waves_waiting_and_its_batch_size(tmp_path):
    problem = Branin()
    with SampleStore(tmp_path / "s.sqlite") as store:
        sampler = Sampler(problem, store, BatchOf(3), progress=False)
        assert sampler.batch_size == 3 and Sampler(problem, store, None, progress=False).batch_size == 1
        X = np.column_stack([np.linspace(-4, 9, 5), np.linspace(1, 14, 5)])
        sampler(X, desc="five")
        sampler(X[:2], desc="found in the store: no round")
        timing = sampler.timing()
        assert timing["rounds"] == 1 and timing["waves"] == 2 and timing["workers"] == 3
        assert timing["waiting_s"] + timing["method_s"] == pytest.approx(timing["wall_s"], abs=1e-3)
        assert 0.0 <= timing["idle_share"] <= 1.0 and sampler.summary()["rounds"] == 1
