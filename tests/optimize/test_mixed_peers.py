"""Each mixed-variable peer proposes allowed designs by its own library's discrete variables (no snapping door in
front of it) and spends its whole budget, on a small problem with a continuous, a grid, an integer and a catalogue
variable."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.optimize.baselines.library import MissingLibraryError
from mechopt.optimize.baselines.mixed_space import allowed_feasible, from_optuna, from_pymoo, snap
from mechopt.optimize.budget import CountedProblem
from mechopt.optimize.methods import METHODS
from mechopt.optimize.variable import Variable
from tests.optimize.mixed_problem import MixedBowl

#: The peers of the mixed-variable benchmark: the library baselines that declare discrete variables.
PEERS = [name for name, m in METHODS.items() if m.discrete and not m.own]
BUDGET = 14
#: SMT refits its mixed Kriging at every step (seconds each): its run is the initial design and two steps, its
#: hyperparameter search from one start.
BUDGETS = {"smt_ego": 7}
OPTIONS = {"smt_ego": {"krg_options": {"n_start": 1}}}


def _counted(budget: int) -> tuple[CountedProblem, MixedBowl]:
    """The bowl as a counted problem without ``snap``: an off-grid proposal would reach the simulator as it is."""
    bowl = MixedBowl()

    def objective(x: np.ndarray) -> float:
        return bowl.evaluate(x)["f"]

    counted = CountedProblem(objective, bowl.bounds, budget, lambda X: bowl.margins(np.atleast_2d(X)).squeeze(-1),
                             vectorized_constraints=True)
    counted.variables = bowl.variables
    return counted, bowl


def test_the_table_names_the_three_library_peers() -> None:
    assert set(PEERS) == {"optuna_tpe", "smt_ego", "pymoo_ga"}
    assert all(METHODS[name].spends_whole_budget for name in PEERS)


@pytest.mark.parametrize("name", PEERS)
def test_peer_proposes_only_allowed_designs_and_spends_its_budget(name: str) -> None:
    budget = BUDGETS.get(name, BUDGET)
    counted, bowl = _counted(budget)
    try:
        res = METHODS[name].function(counted, 0, **OPTIONS.get(name, {}))
    except MissingLibraryError as exc:
        pytest.skip(f"optional library absent: {exc}")
    X = np.array(bowl.calls)
    assert counted.nfev == budget == len(X), res.message
    assert bowl.on_grid(X).all(), X[~bowl.on_grid(X)]
    assert np.array_equal(bowl.snap(X), X)  # bit for bit: one store key per allowed design
    assert len({x.tobytes() for x in X}) == len(X)
    assert bowl.feasible(X).all()
    assert res.success and bowl.on_grid(res.x)[0]


def test_decoders_give_allowed_designs_bit_for_bit() -> None:
    counted, bowl = _counted(5)
    x = from_optuna(counted, {"x0": 0.123, "x1": 0.30000000000000004, "x2": 3, "x3": 0.63})
    assert x.tolist() == [0.123, 0.3, 3.0, 0.63]
    y = from_pymoo(counted, {"x0": 0.5, "x1": 13, "x2": 8, "x3": 1.0})
    assert y.tolist() == [0.5, 1.3, 8.0, 1.0]
    assert np.array_equal(snap(counted, y), y)


def test_allowed_feasible_draws_distinct_feasible_designs_excluding_the_known() -> None:
    counted, bowl = _counted(5)
    rng = np.random.default_rng(0)
    X = allowed_feasible(counted, 50, rng)
    assert X.shape == (50, 4) and bowl.on_grid(X).all() and bowl.feasible(X).all()
    assert len({x.tobytes() for x in X}) == 50
    Y = allowed_feasible(counted, 20, rng, exclude=X)
    assert not {y.tobytes() for y in Y} & {x.tobytes() for x in X}


def test_continuous_problem_keeps_continuous_declarations() -> None:
    optuna = pytest.importorskip("optuna")
    from mechopt.optimize.baselines.mixed_space import has_discrete, optuna_space

    counted = CountedProblem(lambda x: float(np.sum(x**2)), [(0.0, 1.0), (-1.0, 2.0)], 5)
    assert not has_discrete(counted)
    space = optuna_space(optuna, counted)
    assert all(isinstance(d, optuna.distributions.FloatDistribution) and d.step is None for d in space.values())
    counted.variables = (Variable("a", 0.0, 1.0), Variable("n", -1.0, 2.0, integer=True))
    assert has_discrete(counted)
    assert isinstance(optuna_space(optuna, counted)["x1"], optuna.distributions.IntDistribution)
