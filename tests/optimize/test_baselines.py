"""Tests of the budget-limited baseline optimizers (optimize.baselines).

Test problems (3-D, box [-2, 2]^3, both with constraints cutting part of the box):

* QUAD -- weighted shifted sphere ``sum w (x - c)^2`` with the linear constraint ``x1 + x2 + x3 <= 2.4`` active at
  the optimum (known in closed form from the KKT conditions) and an inactive spherical hole.
* RASTRIGIN -- shifted Rastrigin-lite ``sum z^2 + 2 (1 - cos 2 pi z)``, ``z = x - c`` (about 200 local minima in the
  box), global minimum 0 at ``c`` (feasible), a linear cut and a spherical hole elsewhere.

Every objective counts its calls itself and records whether the design was feasible (independently of the
wrapper), so the budget and the "never simulate an infeasible design" claims are checked from outside.
"""

from __future__ import annotations

import numpy as np
import pytest
from recorder import Recorder
from scipy.optimize import check_grad
from scipy.spatial import Delaunay

from mechopt.optimize.baselines import BudgetExhausted, CountedProblem, fit_and_search_rbf
from mechopt.optimize.baselines.bayesian import GaussianProcess, expected_improvement
from mechopt.optimize.baselines.genetic import polynomial_mutation, sbx_crossover
from mechopt.optimize.baselines.powell_penalty import minimize_powell_penalty
from mechopt.optimize.budget import run_multistart
from mechopt.optimize.methods import METHODS

#: The in-house baselines of the table of methods (neither mechopt's own nor a maintained library's).
BASELINES = {n: m.function for n, m in METHODS.items() if not m.own and not m.spends_whole_budget}

BOX = np.array([[-2.0, 2.0]] * 3)

Q_W = np.array([1.0, 2.0, 4.0])
Q_C = np.array([1.2, 0.9, 1.1])
Q_A = np.ones(3)
Q_B = 2.4
Q_HOLE, Q_R = np.array([-1.0, -1.0, 0.0]), 0.8
_LAMBDA = 2.0 * (Q_A @ Q_C - Q_B) / np.sum(Q_A**2 / Q_W)
Q_XSTAR = Q_C - _LAMBDA * Q_A / (2.0 * Q_W)


def quad(x: np.ndarray) -> float:
    return float(np.sum(Q_W * (np.asarray(x) - Q_C) ** 2))


Q_FSTAR = quad(Q_XSTAR)


def quad_margins(x: np.ndarray) -> np.ndarray:
    """Works on one design (d,) or a batch (n, d)."""
    x = np.asarray(x, dtype=float)
    return np.stack([Q_B - x @ Q_A, np.linalg.norm(x - Q_HOLE, axis=-1) - Q_R], axis=-1)


R_C = np.array([0.7, -1.1, 0.4])
R_HOLE = np.array([-1.5, 1.5, -1.5])


def rastrigin(x: np.ndarray) -> float:
    z = np.asarray(x) - R_C
    return float(np.sum(z**2 + 2.0 * (1.0 - np.cos(2.0 * np.pi * z))))


def rastrigin_margins(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return np.stack([3.0 - x[..., 0] - x[..., 2] + x[..., 1], np.linalg.norm(x - R_HOLE, axis=-1) - 1.0], axis=-1)


def make(f, margins, budget: int, vectorized: bool = True, **kw) -> tuple[CountedProblem, Recorder]:
    rec = Recorder(f, margins, BOX)
    return CountedProblem(rec, BOX, budget, margins, vectorized_constraints=vectorized, **kw), rec


# --------------------------------------------------------------------------- accuracy
# method -> (budget, tolerance on f - f*, tolerance on |x - x*|); seed 0; worst of seeds 0-5 observed when set:
# DE 3e-7/3e-4, DA 1e-9/3e-5, NM 5e-6/9e-4, SLSQP 7e-10/2e-5, Powell 2e-15/3e-8, GA 1.4e-4/7e-3,
# SCE 4e-9/4e-5, PSO 1.3e-3/3e-2, BO 1e-2/4e-2.  Random search at the same budgets: f - f* > 0.15.
QUAD_CASES = {
    "differential_evolution": (1500, 1e-5, 2e-3),
    "dual_annealing": (500, 1e-6, 1e-3),
    "nelder_mead": (600, 1e-4, 5e-3),
    "slsqp": (300, 1e-7, 1e-3),
    "cobyqa": (100, 1e-7, 1e-3),  # seeds 0-4: 4e-16 in f, 3e-13 in x; seed 5 4.4e-5 / 4e-3
    "powell_penalty": (1500, 1e-6, 1e-3),
    "genetic": (800, 2e-3, 2e-2),
    "sce_ua": (800, 1e-6, 1e-3),
    "particle_swarm": (1000, 1e-2, 5e-2),
    "bayesian": (60, 3e-2, 0.1),
    "paper000_hybrid": (800, 1e-5, 2e-3),  # seeds 0-5: worst 7.6e-7 in f, 5e-4 in x
}

# Global methods on the multimodal function: at least 2 of seeds 0, 1, 2 must reach the global basin's bottom.
RASTRIGIN_BUDGET, RASTRIGIN_TOL_X = 1500, 1e-2
GLOBAL_METHODS = ["differential_evolution", "dual_annealing", "genetic", "sce_ua", "particle_swarm"]


def test_registry_lists_the_in_house_baselines_with_docs() -> None:
    expected = {"differential_evolution", "dual_annealing", "nelder_mead", "slsqp", "cobyqa", "powell_penalty",
                "genetic", "sce_ua", "particle_swarm", "bayesian", "paper000_hybrid"}
    assert set(BASELINES) == expected
    assert all(METHODS[name].summary for name in expected)
    assert set(QUAD_CASES) == expected


@pytest.mark.parametrize("name", sorted(QUAD_CASES))
def test_reaches_the_constrained_minimum(name: str) -> None:
    budget, tol_f, tol_x = QUAD_CASES[name]
    problem, rec = make(quad, quad_margins, budget)
    res = BASELINES[name](problem, 0)
    assert res.success
    assert rec.is_feasible(res.x)
    assert res.fun - Q_FSTAR <= tol_f, (res.fun, Q_FSTAR)
    assert np.linalg.norm(res.x - Q_XSTAR) <= tol_x
    assert res.fun >= Q_FSTAR - 1e-9  # a feasible design cannot beat the constrained optimum
    assert res.nfev == rec.calls <= budget


@pytest.mark.parametrize("name", GLOBAL_METHODS)
def test_global_methods_find_the_global_minimum_of_rastrigin(name: str) -> None:
    hits = 0
    for seed in range(3):
        problem, rec = make(rastrigin, rastrigin_margins, RASTRIGIN_BUDGET, vectorized=False)
        res = BASELINES[name](problem, seed)
        assert res.nfev == rec.calls <= RASTRIGIN_BUDGET
        hits += np.linalg.norm(res.x - R_C) <= RASTRIGIN_TOL_X
    assert hits >= 2


def _random_search(f, margins, budget: int, seed: int) -> tuple[float, np.ndarray]:
    problem, _ = make(f, margins, budget)
    for x in problem.sample_feasible(budget, np.random.default_rng(seed)):
        problem.evaluate(x)
    return problem.best_f, problem.best_x


def test_tolerances_reject_random_search_at_the_same_budget() -> None:
    # The accuracy tests could fail: a method no better than random sampling would not pass them.
    for name, (budget, tol_f, tol_x) in QUAD_CASES.items():
        f, x = _random_search(quad, quad_margins, budget, 0)
        assert f - Q_FSTAR > tol_f or np.linalg.norm(x - Q_XSTAR) > tol_x, name
    hits = sum(np.linalg.norm(_random_search(rastrigin, rastrigin_margins, RASTRIGIN_BUDGET, s)[1] - R_C)
               <= RASTRIGIN_TOL_X for s in range(3))
    assert hits < 2


# --------------------------------------------------------------------------- budget accounting
@pytest.mark.parametrize("budget", [17, 50, 100])
@pytest.mark.parametrize("name", sorted(BASELINES))
def test_budget_is_respected_and_only_feasible_designs_are_simulated(name: str, budget: int) -> None:
    problem, rec = make(quad, quad_margins, budget)
    res = BASELINES[name](problem, 3)
    assert rec.calls <= budget
    assert res.nfev == rec.calls == problem.nfev
    assert rec.calls >= min(budget, 10)  # the method did use its budget
    assert not any(not ok for ok in rec.feasible), "an infeasible design was simulated"
    assert res.success and rec.is_feasible(res.x)
    # fun is the best value among the simulated feasible designs, and it belongs to x
    best = min(v for v, ok in zip(rec.values, rec.feasible, strict=True) if ok)
    assert res.fun == best == quad(res.x)


@pytest.mark.parametrize("name", sorted(BASELINES))
def test_same_seed_gives_the_same_run(name: str) -> None:
    runs = []
    for _ in range(2):
        problem, rec = make(quad, quad_margins, 40)
        runs.append((BASELINES[name](problem, 7), rec))
    (a, ra), (b, rb) = runs
    assert a.nfev == b.nfev and a.fun == b.fun
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(np.array(ra.xs), np.array(rb.xs))


class SimulationFailed(RuntimeError):
    pass


@pytest.mark.parametrize("name", sorted(BASELINES))
def test_failed_simulations_are_counted_and_never_returned(name: str) -> None:
    def fragile(x: np.ndarray) -> float:
        if x[2] > 1.0:  # a feasible region the "simulator" cannot handle, containing the true optimum
            raise SimulationFailed
        return quad(x)

    problem, rec = make(fragile, quad_margins, 50, failure_errors=(SimulationFailed,))
    res = BASELINES[name](problem, 1)
    assert res.nfev == rec.calls <= 50
    assert res.success and res.x[2] <= 1.0 and np.isfinite(res.fun)


def test_exterior_penalty_may_simulate_infeasible_designs_but_returns_a_feasible_one() -> None:
    problem, rec = make(quad, quad_margins, 1500, simulate_infeasible=True)
    res = minimize_powell_penalty(problem, 0)
    assert not all(rec.feasible)  # the penalty path really used infeasible simulations
    assert rec.is_feasible(res.x)
    assert res.fun - Q_FSTAR <= 1e-3 and res.nfev == rec.calls <= 1500


# --------------------------------------------------------------------------- CountedProblem
def test_counted_problem_budget_cache_and_rejection() -> None:
    problem, rec = make(quad, quad_margins, 3)
    x = np.zeros(3)
    assert problem.evaluate(x) == quad(x)
    assert problem.evaluate(x.copy()) == quad(x) and rec.calls == 1  # cached
    outside = np.array([2.0, 2.0, 2.0])  # violates x1 + x2 + x3 <= 2.4
    assert problem.penalised(outside) == pytest.approx(1e10 + 1e3 * 3.6)
    assert problem.penalised(outside, reject=False) >= 1e10  # no anchor, no simulation
    assert rec.calls == 1
    problem.evaluate(np.ones(3) * 0.1)
    problem.evaluate(outside)  # a direct call is a simulation, infeasible: never the best
    assert rec.calls == 3 and problem.remaining == 0
    with pytest.raises(BudgetExhausted) as info:
        problem.evaluate(np.ones(3) * 0.2)
    assert not info.value.local and rec.calls == 3
    assert problem.best_f == quad(np.ones(3) * 0.1)
    res = problem.result("done")
    assert res.nfev == 3 and res.success and np.all(res.x == 0.1)


def test_sub_budget_and_multistart_split() -> None:
    problem, rec = make(quad, quad_margins, 10)
    with problem.sub_budget(2):
        problem.evaluate(np.zeros(3))
        problem.evaluate(np.full(3, 0.1))
        with pytest.raises(BudgetExhausted) as info:
            problem.evaluate(np.full(3, 0.2))
        assert info.value.local
    assert problem.remaining == 8

    shares = []

    def local_run(x0: np.ndarray) -> None:
        shares.append(problem.available)
        while True:
            problem.evaluate(x0 + 1e-3 * problem.nfev)

    run_multistart(problem, np.zeros((3, 3)), local_run)
    assert shares == [3, 3, 2] and rec.calls == 10


def test_no_feasible_design_gives_an_unsuccessful_result() -> None:
    problem = CountedProblem(quad, BOX, 20, lambda x: np.array([-1.0]))
    res = BASELINES["particle_swarm"](problem, 0)
    assert not res.success and np.all(np.isnan(res.x)) and res.fun == np.inf and res.nfev == 0


def test_extended_objective_is_continuous_at_the_boundary() -> None:
    problem, rec = make(quad, quad_margins, 100)
    anchor = np.zeros(3)
    direction = np.ones(3) / np.sqrt(3.0)
    on_boundary = problem.boundary_point(anchor, anchor + 3.0 * direction)
    assert problem.feasible(on_boundary) and np.sum(on_boundary) == pytest.approx(Q_B, abs=1e-12)
    just_outside = on_boundary + 1e-7 * direction
    assert problem.extended(just_outside, anchor) == pytest.approx(quad(on_boundary), abs=1e-5)
    assert all(rec.feasible)


# --------------------------------------------------------------------------- building blocks
def test_ga_operators_stay_in_the_unit_cube_and_sbx_preserves_the_mean() -> None:
    rng = np.random.default_rng(0)
    for _ in range(200):
        a, b = rng.random(3), rng.random(3)
        c1, c2 = sbx_crossover(a, b, rng)
        m = polynomial_mutation(c1, rng, probability=1.0)
        assert np.all((c1 >= 0) & (c1 <= 1) & (c2 >= 0) & (c2 <= 1) & (m >= 0) & (m <= 1))
    for _ in range(200):
        # Close parents far from the bounds: bounded SBX reduces to the symmetric, mean-preserving form.
        a, b = 0.45 + 0.1 * rng.random(3), 0.45 + 0.1 * rng.random(3)
        c1, c2 = sbx_crossover(a, b, rng)
        np.testing.assert_allclose(c1 + c2, a + b, atol=1e-12)
        m = polynomial_mutation(a, rng, probability=1.0)
        assert np.all(m != a)


def test_gaussian_process_gradient_and_interpolation() -> None:
    rng = np.random.default_rng(1)
    U = rng.random((25, 3))
    y = np.sin(3.0 * U[:, 0]) + U[:, 1] ** 2 - U[:, 2]
    gp = GaussianProcess().fit(U, y, rng=rng)
    theta = np.array([np.log(0.4), np.log(0.7), np.log(1.3), 0.2, np.log(1e-3)])
    err = check_grad(lambda t: gp.neg_log_marginal_likelihood(t)[0],
                     lambda t: gp.neg_log_marginal_likelihood(t)[1], theta)
    assert err < 1e-4 * (1.0 + np.linalg.norm(gp.neg_log_marginal_likelihood(theta)[1]))
    mean, std = gp.predict(U)
    np.testing.assert_allclose(mean, y, atol=2e-2)
    assert np.all(std < 0.05)
    ei = expected_improvement(np.array([0.0, 1.0]), np.array([1e-9, 0.5]), best=0.5)
    assert ei[0] == pytest.approx(0.5) and ei[1] > 0.0


# --------------------------------------------------------------------------- RBF / Kriging surrogate baseline
@pytest.fixture(scope="module")
def quad_samples() -> tuple[np.ndarray, np.ndarray]:
    problem = CountedProblem(quad, BOX, 0, quad_margins, vectorized_constraints=True)
    X = problem.sample_feasible(60, np.random.default_rng(0))
    return X, np.array([quad(x) for x in X])


@pytest.mark.parametrize(("surrogate", "tol_f"), [("kriging", 1e-3), ("rbf", 5e-2)])
def test_surrogate_baseline_finds_the_minimum_from_given_samples(quad_samples, surrogate, tol_f) -> None:
    X, y = quad_samples
    problem, rec = make(quad, quad_margins, 5)
    res = fit_and_search_rbf(X, y, problem, surrogate=surrogate, n_search=2**14)
    assert res.nfev == rec.calls == 1 and rec.is_feasible(res.x)
    assert res.fun == quad(res.x)
    assert res.fun - Q_FSTAR <= tol_f
    assert res.fun < np.min(y)  # better than the best given sample


def test_surrogate_baseline_hull_restriction_and_no_evaluation(quad_samples) -> None:
    X, y = quad_samples
    problem, rec = make(quad, quad_margins, 5)
    res = fit_and_search_rbf(X, y, problem, within_hull=True, evaluate=False, n_search=2**13)
    assert res.hull and res.nfev == 0 and rec.calls == 0
    assert Delaunay(problem.to_unit(X)).find_simplex(problem.to_unit(res.x)[None, :])[0] >= 0
    assert rec.is_feasible(res.x)
