"""``mechopt.minimize`` on problems defined here, in the test file alone, with no edit of the package: a closed-form
2-variable problem with one constraint through the store, a smooth 4-D function, the ventilator's refinement
accounting, and the fingerprint that keeps different studies' samples apart."""

from __future__ import annotations

import numpy as np
import pytest

import mechopt
from mechopt.runs.sampling import sample_designs
from mechopt.runs.store import SampleStore
from mechopt.sim.four_bar.load import RockerLoad
from mechopt.sim.four_bar.problem import FourBarProblem

#: The ventilator's true optimum, T_RMS in N·m (brute force: see test_ground_truth.py).
T_TRUE = 1.7582


class Bracket(mechopt.DesignProblem):
    """Mass-like objective pulled towards (1.3, 1.2) mm and kept inside a disc of radius 1.5 mm.

    The constrained optimum is the disc's point towards (1.3, 1.2): x* = 1.5 (1.3, 1.2) / |(1.3, 1.2)|, with
    f* = 1 + (|(1.3, 1.2)| − 1.5)².
    """

    name = "bracket"
    variables = (mechopt.Variable("a", 0.0, 2.0, "mm"), mechopt.Variable("b", 0.0, 2.0, "mm"))
    constraints = ("disc_mm2",)
    outputs = ("f",)
    objective = "f"

    def margins(self, X):
        return (1.5**2 - X[:, 0] ** 2 - X[:, 1] ** 2)[:, None]

    def evaluate(self, x):
        return {"f": 1.0 + (x[0] - 1.3) ** 2 + (x[1] - 1.2) ** 2}


R = np.hypot(1.3, 1.2)
X_STAR = 1.5 * np.array([1.3, 1.2]) / R
F_STAR = 1.0 + (R - 1.5) ** 2


def test_a_problem_defined_in_a_test_file_is_minimised_through_the_store(tmp_path):
    store = tmp_path / "bracket.sqlite"
    result = mechopt.minimize(Bracket(), budget=60, method="sparse", store=store, seed=1)
    assert result.success and result.nfev <= 60
    np.testing.assert_allclose(result.x, X_STAR, atol=2e-3)
    assert result.fun == pytest.approx(F_STAR, rel=1e-4)
    assert result.outputs["f"] == result.fun and result.nnew == result.nfev
    # The same call again: every design comes from the store, none is simulated twice.
    again = mechopt.minimize(Bracket(), budget=60, method="sparse", store=store, seed=1)
    assert again.nnew == 0 and again.nreused == again.nfev
    np.testing.assert_array_equal(again.x, result.x)


class Smooth4(mechopt.DesignProblem):
    """A smooth, non-separable 4-D bowl with its minimum inside the box (known in closed form)."""

    name = "smooth4"
    variables = tuple(mechopt.Variable(n, 0.0, 10.0) for n in ("w", "x", "y", "z"))
    outputs = ("f",)
    objective = "f"
    CENTER = np.array([3.1, 6.4, 4.7, 2.2])

    def evaluate(self, x):
        d = np.asarray(x) - self.CENTER
        return {"f": 2.0 + 0.05 * d @ d + 0.02 * d[0] * d[1] + 0.01 * (d[2] - d[3]) ** 2 + 0.001 * np.sum(d**4)}


def test_the_pipeline_finds_the_minimum_of_a_smooth_4d_function():
    result = mechopt.minimize(Smooth4(), budget=300, method="sparse", seed=0, options={"refine": False})
    # The model alone (10 lines at Fekete nodes, no local search) is within 0.5 % of the minimum, 2.0.
    assert result.fun <= 2.0 * 1.005
    assert result.stages[0].plan.dim == 4 and result.nfev <= 300


def test_refinement_improves_on_the_model_candidate_within_the_budget(ventilator):
    problem = mechopt.load_study("ventilator", {"engine": "analytic"}).problem
    # The small first plan of a small budget (3 lines of 4 samples) misses the optimum, which lies on the region's
    # boundary: the model's steps and the local search on the simulator must take over, within the budget.
    result = mechopt.minimize(problem, budget=40, method="sparse", seed=0, options={"search_points": 200_000})
    global_stage, stepped, *refined = result.stages
    assert stepped.name == "model steps" and stepped.n_samples > 0
    # SLSQP may stop with budget left (a converged search): steps on the corrected model then use it.
    assert [s.name for s in refined] in ([], ["local refinement"], ["corrected steps"],
                                         ["local refinement", "corrected steps"])
    assert result.nfev <= 40
    assert sum(s.n_samples for s in result.stages) + 1 <= 40
    # The model's candidate was simulated, not taken from the model.
    assert np.isfinite(global_stage.simulated) and global_stage.simulated != global_stage.predicted
    assert min(s.simulated for s in result.stages[1:]) < global_stage.simulated
    assert result.fun == min(s.simulated for s in result.stages)
    assert problem.feasible(result.x)[0]
    assert result.fun < T_TRUE * 1.005


@pytest.mark.parametrize("method", ["slsqp", "differential_evolution"])
def test_baselines_run_through_the_same_entry_point(method):
    result = mechopt.minimize(Bracket(), budget=80, method=method, seed=0)
    assert result.success and result.nfev <= 80 and result.method == method
    assert result.fun == pytest.approx(F_STAR, rel=2e-2)


@pytest.mark.parametrize(("kwargs", "expected"), [
    ({"budget": 2}, "budget = 2"),
    ({"method": "magic"}, "method = 'magic'"),
    ({"seed": -1}, "seed = -1"),
    ({"workers": 0}, "workers = 0"),
    ({"method": "sparse", "options": {"n_lines": "seven"}}, "n_lines = 'seven'"),
    ({"method": "sparse", "options": {"lines": 7}}, "unknown option lines"),
    ({"options": {"n_lines": 7}}, "unknown option 'n_lines' of method 'auto'; expected one of front"),
    ({"method": "slsqp", "options": {"n_starts": 1.5}}, "method 'slsqp': n_starts = 1.5: expected int"),
    ({"store": 123}, "store = 123"),
    ({"method": "sparse", "budget": 6}, "needs at least 2 samples on each of its 3 lines + 1 = 7"),
    ({"x0": [2.5, 0.0]}, "x0 design [2.5, 0.0]: a = 2.5 lies outside [0, 2] mm"),
    ({"x0": [1.5, 1.5]}, "x0 design a=1.5 mm, b=1.5 mm violates the declared constraints: disc_mm2 = -2.25"),
    ({"x0": [1.0]}, "x0 of shape (1,): expected (2,) or (m, 2) for the variables a, b"),
    ({"x0": [[0.1, float("inf")]]}, "x0 design [0.1, inf] is not finite"),
    ({"x0": np.full((50, 2), 0.5)}, "x0 holds 50 designs and the budget is 50"),
    ({"x0": np.full((35, 2), 0.5), "method": "sparse-global"}, "x0's 35 designs count in budget = 50, which leaves "
     "15 to the method: budget = 15: method 'sparse-global' needs at least 10d = 20"),
])
def test_bad_arguments_are_one_line_errors_before_any_work(kwargs, expected):
    with pytest.raises(mechopt.InputError) as info:
        mechopt.minimize(Bracket(), **{"budget": 50, **kwargs})
    assert expected in str(info.value) and "\n" not in str(info.value)


def _negated(load: RockerLoad) -> RockerLoad:
    return RockerLoad(load.breaks, -np.asarray(load.coefs))


def test_studies_that_differ_only_in_the_load_or_the_toggle_margin_never_share_samples(ventilator, tmp_path):
    base = mechopt.load_study("ventilator", {"engine": "analytic"}).problem
    m = base.mechanism
    # The same sum of |spline coefficients| (the old cache key), a different load.
    other_load = FourBarProblem(type(m)(**{**m.__dict__, "load": _negated(m.load)}), base.box, "analytic",
                                base.name)
    other_margin = FourBarProblem(type(m)(**{**m.__dict__, "toggle_margin_deg": 16.0}), base.box, "analytic",
                                  base.name)
    assert np.sum(np.abs(other_load.mechanism.load.coefs)) == np.sum(np.abs(m.load.coefs))
    prints = {base.fingerprint(), other_load.fingerprint(), other_margin.fingerprint()}
    assert len(prints) == 3
    designs = [(53.0, 65.0, 282.0), (40.0, 80.0, 270.0)]
    with SampleStore(tmp_path / "s.sqlite") as store:
        first = sample_designs(designs, base, store, progress=False)
        assert first.n_computed == 2
        for problem in (other_load, other_margin):
            res = sample_designs(designs, problem, store, progress=False)
            assert res.n_cached == 0 and res.n_computed == 2
        # Same settings: reused.
        assert sample_designs(designs, base, store, progress=False).n_cached == 2
    # And the load really changes the answer.
    assert base.evaluate(np.array(designs[0]))["t_rms"] != other_load.evaluate(np.array(designs[0]))["t_rms"]


def test_trust_report_says_whether_the_model_resolves_the_landscape():
    from mechopt.studies.benchmark_functions import Hartmann3

    # A smooth bowl cut by a disc: 7 lines resolve it, the model's claim and its leave-one-line-out error agree.
    smooth = mechopt.minimize(Bracket(), budget=200, method="sparse", seed=1)
    assert smooth.trust["resolved"] and smooth.trust["lolo_median"] < 0.05
    assert smooth.trust["verdict"].startswith("the global model resolves the landscape")
    # Hartmann-3 (four basins, the global one narrow): the same plan cannot resolve it, and says so.
    rough = mechopt.minimize(Hartmann3(), budget=150, method="sparse", seed=0)
    assert not rough.trust["resolved"] and rough.trust["lolo_median"] > 0.05
    assert "does not resolve" in rough.trust["verdict"] and "sparse-global" in rough.trust["verdict"]


def test_a_variable_narrower_than_the_store_resolves_is_refused_in_one_line():
    # The store keys designs to 9 decimals: a range of 1e-7 mm holds 100 keys per variable, and the default
    # method's steps came back as designs already simulated (19 of a budget of 30 were new).
    with pytest.raises(mechopt.InputError) as info:
        mechopt.Variable("gap", 1.0, 1.0000001, "mm")
    assert str(info.value).startswith("variable gap: bounds [1.0, 1.0000001] span 1e-07, expected at least 1e-06 mm")
    assert mechopt.Variable("gap", 1.0, 1.000001, "mm").upper == 1.000001


class _Nowhere(Bracket):
    """The disc moved out of the box: no design satisfies the constraint."""

    def margins(self, X):
        return (1.5**2 - (X[:, 0] - 9.0) ** 2 - X[:, 1] ** 2)[:, None]

    def evaluate(self, x):
        raise AssertionError("nothing may be simulated")


class _Raises(Bracket):
    def margins(self, X):
        return {}["disc_mm2"]


@pytest.mark.parametrize("method", ["auto", "sparse", "sparse-global", "slsqp", "optuna_tpe"])
def test_an_empty_feasible_region_or_a_raising_margin_is_one_line_before_any_simulation(method):
    # auto crashed in numpy ("zero-size array to reduction operation fmax"), sparse raised its own SurrogateError,
    # the others simulated nothing and returned NaN: each failed its own way.
    with pytest.raises(mechopt.InputError) as info:  # the largest margin: 1.5² − (2 − 9)² at the corner (2, 0)
        mechopt.minimize(_Nowhere(), budget=30, method=method)
    assert str(info.value) == ("problem 'bracket': none of 16384 designs spread over the box satisfies the declared "
                               "constraints (largest margins: disc_mm2 -46.8); expected some design with every margin "
                               ">= 0: check the bounds and the margins' signs")
    with pytest.raises(mechopt.InputError, match=r"^bracket: margins raised KeyError: 'disc_mm2'$"):
        mechopt.minimize(_Raises(), budget=30, method=method)


def test_names_given_as_one_string_are_refused():
    class Strings(Bracket):
        outputs = "f"

    with pytest.raises(mechopt.InputError, match=r"outputs = 'f'; expected a tuple of names such as \('f',\)"):
        mechopt.minimize(Strings(), budget=30)


class _Counting(Bracket):
    """The bracket, counting its simulations."""

    calls = 0

    def evaluate(self, x):
        type(self).calls += 1
        return super().evaluate(x)


@pytest.mark.parametrize("method", ["auto", "nelder_mead", "sparse-global"])
def test_x0_counts_in_the_budget_and_the_answer_is_never_worse(method, tmp_path):
    # The current design at the constrained optimum (a closed form): no method may answer worse, and x0 is paid
    # for out of the budget, not on top of it.
    _Counting.calls = 0
    current = X_STAR * (1 - 1e-9)
    result = mechopt.minimize(_Counting(), budget=30, method=method, seed=0, x0=[[0.2, 0.2], current],
                              store=tmp_path / "s.sqlite")
    assert _Counting.calls == result.nnew <= 30 and result.nfev <= 30
    assert result.success and result.fun <= Bracket().evaluate(current)["f"]
    with SampleStore(tmp_path / "s.sqlite") as store:
        assert store.count(_Counting().fingerprint()) == result.nnew


def test_auto_starts_its_model_from_x0():
    # x0 stands in for as many of auto's Sobol designs: the budget is spent exactly, x0 included.
    _Counting.calls = 0
    x0 = np.array([[0.5, 0.5], [1.0, 0.2], [0.1, 1.4]])
    result = mechopt.minimize(_Counting(), budget=12, seed=3, x0=x0)
    assert _Counting.calls == result.nfev == 12
    assert result.fun == pytest.approx(F_STAR, abs=0.02)
