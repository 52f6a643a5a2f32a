"""The default method ``auto`` (mechopt.optimize.auto): plan, budget, failures, convergence, refusals."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import approx_fprime
from scipy.stats import qmc

from mechopt import minimize
from mechopt.errors import InputError
from mechopt.optimize.auto import auto_search, choose_plan
from mechopt.optimize.auto.acquisition import propose_batch
from mechopt.optimize.auto.gp import GaussianProcess, _median_spacing, _neg_log_posterior, _sees_no_neighbour, fit_gp
from mechopt.optimize.auto.transform import standardise
from mechopt.optimize.problem import DesignProblem, Variable
from mechopt.studies.benchmark_functions import SUITE, FailingHartmann3, Hartmann3, Hartmann6


class Quadratic(DesignProblem):
    """(x − c)ᵀ A (x − c) + 2 with a known minimiser c inside the box and a tilted, anisotropic A."""

    name = "quadratic"
    variables = (Variable("a", -1.0, 3.0), Variable("b", 0.0, 2.0), Variable("c", -2.0, 2.0))
    outputs = ("f",)
    objective = "f"
    centre = np.array([1.3, 0.4, -0.7])
    A = np.array([[3.0, 1.0, 0.0], [1.0, 2.0, 0.5], [0.0, 0.5, 1.0]])

    def evaluate(self, x):
        t = np.asarray(x) - self.centre
        return {"f": float(t @ self.A @ t + 2.0)}


def test_auto_says_its_plan():
    r = minimize(Hartmann3(), 12, method="auto", seed=1)
    assert r.method == "auto" and r.plan == "global"
    assert "plan global" in r.message and r.nfev == 12


def test_plan_follows_dimension_and_budget():
    assert choose_plan(3, 30).name == "global"
    assert choose_plan(6, 300).name == "global" and choose_plan(12, 26).name == "global"
    # The initial design leaves at least a quarter of a short budget to the model.
    short = choose_plan(6, 14)
    assert short.n_init <= 14 - 3 and choose_plan(6, 300).n_init == 14


def test_a_budget_beyond_the_global_gps_size_goes_on_in_a_trust_region(monkeypatch):
    # The global GP's fit grows as n³ (branin at 600: 130 s of the method's own time before, 73 s after): beyond
    # plan.GLOBAL_MAX_POINTS designs the trust-region plan takes over.  Here the size is 14 so the handover happens
    # within a test's budget; the closed-form minimum must still be found and the budget spent exactly.
    import mechopt.optimize.auto.search as search

    monkeypatch.setattr(search, "GLOBAL_MAX_POINTS", 14)
    calls = []
    real = search._trust_region_plan
    monkeypatch.setattr(search, "_trust_region_plan",
                        lambda run, plan: calls.append(run.values.size) or real(run, plan))
    p = Quadratic()
    r = auto_search(lambda X: np.array([p.evaluate(x)["f"] for x in np.atleast_2d(X)]),
                    np.array(p.bounds, dtype=float), 40, seed=3)
    assert calls == [14] and r.nfev == 40 == len(np.unique(r.X, axis=0))
    np.testing.assert_allclose(r.x, p.centre, atol=0.03)
    assert r.fun == pytest.approx(2.0, abs=2e-3)
    assert "one global GP, expected improvement up to 300 designs, then a restarted trust region" in choose_plan(
        3, 600).describe(3, 600)


def test_hartmann3_global_basin_at_30():
    p = Hartmann3()
    r = minimize(p, 30, method="auto", seed=0)
    assert r.nfev == 30
    assert p.in_global_basin(r.x)
    assert p.gap(r.fun) < 0.01


def test_incumbent_on_a_face_is_tested_inside():
    """Hartmann-3 varies by 0.2 % of its range along x1 from its minimiser (x1 = 0.115) to the face x1 = 0: the GP
    takes x1 for irrelevant and expected improvement refines x2, x3 on the face.  Seeds 3, 4, 5 and 9 of 10 ended
    there at a gap of 0.204 % before the polish probed inside the face; measured after: 0.0036 %, 0.0050 %,
    0.0075 %, 0.0039 % (with the fits' looser tolerance of 6ab804d: 0.00007 %, 0.011 %, 0.00007 %, 0.00007 %).
    The bound is a tenth of the gap on the face."""
    p = Hartmann3()
    F = lambda X: p.function(np.atleast_2d(X))  # noqa: E731
    for seed in (3, 4):
        r = auto_search(F, np.array(p.bounds, dtype=float), 30, seed=seed)
        assert r.x[0] > 0.05
        assert p.gap(r.fun) < 2e-4


def test_quadratic_closed_form_minimum():
    p = Quadratic()
    r = minimize(p, 30, method="auto", seed=3)
    np.testing.assert_allclose(r.x, p.centre, atol=0.02)
    assert r.fun == pytest.approx(2.0, abs=1e-3)


def test_6d_small_budget_spends_exactly_its_budget():
    r = minimize(Hartmann6(), 20, method="auto", seed=0)
    assert r.plan == "global" and r.nfev == 20 and r.success
    assert r.fun < -0.5  # better than a typical random design (the mean of Hartmann-6 over the box is about −0.26)


def test_hartmann6_at_60_on_the_global_model():
    # The global model runs 6 variables (plan.py): seeds 0-2 end 1.4e-6, 6.6e-7 and 3.9e-7 of the range from the
    # minimum; the trust regions that ran them before (8908c10) ended 8.3e-5, 6.0e-5 and 2.1e-6 from it.
    p = Hartmann6()
    gaps = [p.gap(minimize(p, 60, method="auto", seed=seed).fun) for seed in range(3)]
    assert max(gaps) < 1e-5


def test_batches_spend_exactly_the_budget_on_distinct_designs():
    p = Hartmann3()
    res = auto_search(p, p.bounds, 17, seed=2, batch=3)
    assert res.nfev == 17 and res.X.shape == (17, 3)
    assert np.unique(np.round(res.X, 9), axis=0).shape[0] == 17


def test_steps_walk_onto_an_active_constraint():
    # min −(x + 2y) + 0.3 sin 5x on the quarter disc x² + y² <= 1: the optimum −2.2444054 (x = 0.74667, y = 0.66520,
    # by a dense scan of the arc) lies on the arc.  Steps that only reject infeasible candidates end 1e-4 to 1e-3 of
    # the margin inside it (−2.2414 to −2.2440 on these seeds) with no design on it.
    def margins(X):
        X = np.atleast_2d(X)
        return (1.0 - X[:, 0] ** 2 - X[:, 1] ** 2)[:, None]

    def f(X):
        X = np.atleast_2d(X)
        return -(X[:, 0] + 2 * X[:, 1]) + 0.3 * np.sin(5 * X[:, 0])

    bounds = np.array([[0.0, 1.2], [0.0, 1.2]])
    for seed in range(3):
        r = auto_search(f, bounds, 20, seed=seed, feasible=lambda X: margins(X)[:, 0] >= 0, margins=margins)
        assert r.fun - (-2.2444054) < 1e-5 and margins(r.x)[0, 0] >= 0
        assert np.sum(np.abs(margins(r.X)[:, 0]) < 1e-5) >= 5


def test_sparse_candidates_move_any_number_of_the_centres_coordinates():
    from mechopt.optimize.auto.acquisition import _candidates

    rng = np.random.default_rng(0)
    lo, hi, centre = np.zeros(8), np.ones(8), np.full(8, 0.5)
    moved = np.sum(_candidates(lo, hi, centre, 1024, rng)[1024:] != centre, axis=1)
    assert moved.min() == 8  # TuRBO's rule below 20 variables: every coordinate, the Sobol points again
    moved = np.sum(_candidates(lo, hi, centre, 1024, rng, sparse=True)[1024:] != centre, axis=1)
    counts = np.bincount(moved, minlength=9)[1:]
    assert counts.sum() == 1024 and counts.min() > 80  # 1 to 8 coordinates, each about 128 times


def test_joint_posterior_draws_have_the_posterior_mean_and_covariance():
    rng = np.random.default_rng(3)
    X = rng.random((8, 2))
    gp = GaussianProcess(X, np.sin(4 * X[:, 0]) + X[:, 1], np.array([np.log(0.4), np.log(0.6), 0.0, np.log(1e-6)]))
    U = np.array([[0.2, 0.3], [0.25, 0.3], [0.9, 0.9], X[0]])
    F = gp.draw(U, 20000, rng)
    mean, sd = gp.predict(U)
    assert np.all(np.abs(F.mean(0) - mean) < 5 * sd / np.sqrt(20000) + 1e-3)
    assert np.allclose(F.std(0)[:3], sd[:3], rtol=0.03)
    assert abs(F[:, 3].mean() - gp.y[0]) < 2e-3  # a simulated design is drawn at its value
    # Nearby designs are drawn together: their correlation is the posterior's, not zero.
    assert np.corrcoef(F[:, 0], F[:, 1])[0, 1] > 0.9


def test_kriging_believer_improves_on_the_believed_design_not_next_to_it():
    # A bowl between designs: the first design goes to its bottom, believed below the incumbent.  Measured against the
    # unchanged incumbent, the second went 0.017 from the first, where the model expects the same improvement.
    X = np.array([[0.0], [0.2], [0.6], [0.8], [1.0]])
    y = 10.0 * (X[:, 0] - 0.4) ** 2
    gp = GaussianProcess(X, y, np.array([np.log(0.3), 0.0, np.log(1e-10)]), quadratic=False)
    U = propose_batch(gp, float(y.min()), np.zeros(1), np.ones(1), X[1], 2, np.random.default_rng(0),
                      lambda C: np.ones(C.shape[0], dtype=bool))
    assert abs(U[0, 0] - 0.4) < 0.05
    assert abs(U[1, 0] - U[0, 0]) > 0.05


def test_believed_designs_are_exact_under_a_nugget():
    rng = np.random.default_rng(1)
    X = rng.random((10, 2))
    gp = GaussianProcess(X, np.sin(3 * X[:, 0]) + X[:, 1], np.array([np.log(0.4), np.log(0.4), 0.0, np.log(0.1)]))
    u = np.array([[0.5, 0.5]])
    # With the noise on the believed design, 0.25 of the 0.39 before was left.
    assert gp.believe(u).predict(u)[1][0] < 1e-3 * gp.predict(u)[1][0]


def test_trust_region_batches_of_8_find_the_hartmann6_basin_at_62_simulations(monkeypatch):
    # Thompson batches: the kriging believer's batches of 8 reached −2.70, −1.96, −2.37 on these seeds.  The trust
    # regions continue a budget beyond the global GP's size; a size of 14 hands over right after the Sobol design.
    import mechopt.optimize.auto.search as search

    monkeypatch.setattr(search, "GLOBAL_MAX_POINTS", 14)
    p = Hartmann6()
    runs = [auto_search(p, p.bounds, 62, seed=seed, batch=8) for seed in range(3)]
    assert all(np.unique(np.round(r.X, 9), axis=0).shape[0] == 62 for r in runs)
    assert np.median([r.fun for r in runs]) < -3.0  # the global minimum is −3.3224


def test_runs_in_12_dimensions():
    def sphere(X):
        return np.sum((np.atleast_2d(X) - 0.3) ** 2, axis=1)

    bounds = np.array([[-1.0, 1.0]] * 12)
    res = auto_search(sphere, bounds, 60, seed=0)
    assert res.nfev == 60 and res.plan.name == "global"
    assert res.fun < np.min(res.values[: res.plan.n_init])  # the model's steps improved on the initial design


def test_failure_region_is_learned_not_raised():
    p = FailingHartmann3()
    r = minimize(p, 40, method="auto", seed=0)
    assert r.success and r.nfev == 40
    assert r.x[0] <= p.raise_above and r.x[1] <= p.nan_above
    assert 0 < r.nfailed < 20  # failures happen (a fifth of the box fails) and are counted, and then avoided
    assert f"{r.nfailed} failed" in r.message


def test_budget_below_2d_plus_2_refused_in_one_line():
    with pytest.raises(InputError) as info:
        minimize(Hartmann6(), 13, method="auto")
    assert "2d + 2 = 14" in str(info.value) and "\n" not in str(info.value)


def test_no_design_satisfying_the_constraints_ends_the_search_with_the_reason():
    # minimize refuses such a problem before it starts (DesignProblem.check_region); the search itself, given one,
    # says why it simulated nothing instead of fitting a model to no designs.
    from mechopt.optimize.auto.search import auto_search

    r = auto_search(lambda X: np.sum(X * X, axis=1), np.array([[0.0, 1.0]] * 3), 20, seed=0,
                    feasible=lambda X: np.zeros(len(X), dtype=bool))
    assert r.nfev == 0 and np.isnan(r.fun) and np.isnan(r.x).all()
    assert r.message.endswith("no design tried satisfies the declared constraints")


def test_gp_gradient_and_fit():
    rng = np.random.default_rng(0)
    X = rng.random((25, 3))
    y = np.sin(6 * X[:, 0]) + X[:, 1] ** 2
    y = (y - y.mean()) / y.std()
    # Without and with the additive component's variance (the last entry).
    for theta in (np.array([-1.0, -0.3, 0.5, 0.2, np.log(1e-3)]), np.array([-1.0, -0.3, 0.5, 0.2, -7.0, -0.7])):
        for w in (0.0, 1.0):
            grad = _neg_log_posterior(theta, X, y, 1.9, w)[1]
            fd = approx_fprime(theta, lambda t, w=w: _neg_log_posterior(t, X, y, 1.9, w)[0], 1e-6)
            np.testing.assert_allclose(grad, fd, rtol=1e-4, atol=1e-4)
    gp = fit_gp(X, y, rng)
    mean, sd = gp.predict(X)
    np.testing.assert_allclose(mean, y, atol=0.05)  # a near-noiseless function is interpolated
    assert np.all(sd < 0.1)
    # x3 does not enter y: its length-scale is the longest.
    assert np.argmax(gp.theta[:3]) == 2


def test_an_additive_function_is_told_from_an_interaction_by_the_evidence():
    # f = g1(x1) + g2(x2) + g3(x3): the evidence puts the variance on the additive component, and the model then
    # predicts combinations of the variables no design has, from what each variable did elsewhere.  A product of
    # the same three terms gets it on the product (Matérn) component, and the additive one is left out.
    rng = np.random.default_rng(1)
    X, U = rng.random((30, 3)), rng.random((500, 3))
    terms = lambda X: (np.sin(6 * X[:, 0]), np.cos(5 * X[:, 1]), 2.0 * X[:, 2] ** 2)  # noqa: E731
    for combine, additive in ((lambda t: t[0] + t[1] + t[2], True), (lambda t: t[0] * t[1] * t[2], False)):
        y, truth = combine(terms(X)), combine(terms(U))
        scale, level = y.std(), y.mean()
        gp = fit_gp(X, (y - level) / scale, rng, prior=False)
        if not additive:
            assert gp.theta.size == 5  # the component left out of the model: the product kernel alone
        else:
            share = np.exp(gp.theta[5]) / (np.exp(gp.theta[5]) + np.exp(gp.theta[3]))  # additive / total
            assert share > 0.95
            error = gp.predict(U)[0] * scale + level - truth
            assert np.max(np.abs(error)) < 0.05 * np.ptp(truth)


def test_a_deterministic_function_is_interpolated_to_its_resolution():
    # A simulator is deterministic: the noise is fitted down to the floor, which is for the factorisation only.
    # With a floor of 1e-6 the model missed its own designs by 1.1e-4 standard deviations, and a minimiser could
    # not see the last differences a valley's designs had resolved.
    rng = np.random.default_rng(3)
    X = rng.random((30, 2))
    y = (X[:, 0] - 0.3) ** 2 + 2.0 * (X[:, 1] - 0.6) ** 2 + 0.3 * np.sin(5.0 * X[:, 0])
    y = (y - y.mean()) / y.std()
    gp = fit_gp(X, y, rng, prior=False)
    assert np.exp(gp.theta[3]) < 1e-8  # the noise variance (d + 1)
    np.testing.assert_allclose(gp.predict(X)[0], y, atol=1e-6)


def test_designs_a_hair_apart_factorise_with_jitter():
    rng = np.random.default_rng(0)
    X = rng.random((20, 3))
    X = np.vstack([X, X[:5] + 1e-13])  # what a believer's batch or a polish next to the incumbent can give
    y = np.sin(3.0 * X.sum(axis=1))
    gp = GaussianProcess(X, y, np.array([np.log(0.3)] * 3 + [0.0, np.log(1e-20)]))
    mean, sd = gp.predict(X[:5])
    assert np.all(np.isfinite(mean)) and np.all(np.isfinite(sd))
    np.testing.assert_allclose(mean, y[:5], atol=1e-4)


def _matern52(A: np.ndarray, B: np.ndarray, ell) -> np.ndarray:
    """Matérn-5/2 correlation of designs A and B, written out for the independent formulations below."""
    D = (A[:, None, :] - B[None, :, :]) / ell
    r = np.sqrt(np.sum(D * D, axis=2))
    return (1 + np.sqrt(5) * r + 5 / 3 * r * r) * np.exp(-np.sqrt(5) * r)


def test_mean_level_is_the_limit_of_a_random_constant_of_large_variance():
    # An independent formulation: a zero-mean GP whose kernel has a constant term B·11ᵀ predicts, as B grows, the
    # generalised least-squares level plus the kriging of the residuals (ordinary kriging, Santner et al. 2003).
    rng = np.random.default_rng(5)
    X = np.vstack([0.1 * rng.random((9, 2)), rng.random((3, 2))])  # a cluster in a corner and three apart
    y = np.concatenate([-1.0 + 0.1 * rng.standard_normal(9), [1.0, 1.5, 0.8]])
    theta = np.array([np.log(0.15), np.log(0.2), 0.0, np.log(1e-6)])
    gp = GaussianProcess(X, y, theta, quadratic=False)  # 12 designs would carry the quadratic trend by default
    U = np.array([[0.05, 0.05], [0.5, 0.5], [0.95, 0.9], [3.0, 3.0]])

    def k(A, B):
        return _matern52(A, B, np.exp(theta[:2]))

    K, Ks, big = k(X, X) + 1e-6 * np.eye(12), k(U, X), 1e5
    mean, sd = gp.predict(U)
    np.testing.assert_allclose(mean, (Ks + big) @ np.linalg.solve(K + big, y), atol=1e-4)
    # The level is plugged in as known (its uncertainty is left out, as BoTorch does): simple kriging's variance.
    np.testing.assert_allclose(sd**2, np.maximum(1.0 - np.sum(Ks * np.linalg.solve(K, Ks.T).T, axis=1), 1e-12))
    # Far from every design the model expects the level, not the average the cluster drags down.
    k1 = np.linalg.solve(K, np.ones(12))
    assert abs(mean[3] - k1 @ y / k1.sum()) < 1e-9
    assert mean[3] > y.mean() + 0.3


def test_quadratic_trend_is_the_limit_of_random_coefficients_of_large_variance():
    # Universal kriging (Santner et al. 2003): a zero-mean GP whose kernel has the term B·f(u)ᵀf(v), f = (1, u_k,
    # u_k²), predicts, as B grows, the generalised least-squares trend plus the kriging of the residuals.
    rng = np.random.default_rng(11)
    X = rng.random((14, 3))
    y = np.sin(4.0 * X[:, 0]) + (X[:, 1] - 0.3) ** 2 - X[:, 2]
    theta = np.array([np.log(0.4)] * 3 + [0.0, np.log(1e-6)])
    gp = GaussianProcess(X, y, theta, quadratic=True)
    U = np.array([[0.5, 0.5, 0.5], [0.9, 0.1, 0.2], [1.5, -0.5, 2.0]])

    def f(A):
        return np.hstack([np.ones((A.shape[0], 1)), A, A * A])

    def k(A, B):
        return _matern52(A, B, 0.4)

    big = 1e6
    K = k(X, X) + 1e-6 * np.eye(14) + big * f(X) @ f(X).T
    mean, _ = gp.predict(U)
    np.testing.assert_allclose(mean, (k(U, X) + big * f(U) @ f(X).T) @ np.linalg.solve(K, y), atol=1e-4)


def test_a_bowl_without_cross_terms_is_reproduced_far_from_the_designs():
    # A function of the trend's class is its own prediction: nothing is left for the kriging of residuals.  With a
    # constant mean the model reverts to the level away from the designs.
    rng = np.random.default_rng(12)
    X = 0.4 * rng.random((10, 2))  # designs in one corner
    bowl = lambda U: 3.0 * (U[:, 0] - 0.7) ** 2 + 0.5 * (U[:, 1] - 0.2) ** 2 - 1.0  # noqa: E731
    theta = np.array([np.log(0.3), np.log(0.3), 0.0, np.log(1e-6)])
    U = np.array([[0.7, 0.2], [1.0, 1.0], [0.9, 0.6]])
    np.testing.assert_allclose(GaussianProcess(X, bowl(X), theta, quadratic=True).predict(U)[0], bowl(U), atol=1e-6)
    assert abs(GaussianProcess(X, bowl(X), theta, quadratic=False).predict(U[:1])[0][0] - bowl(U[:1])[0]) > 0.1


def test_the_quadratic_trend_is_taken_only_where_the_designs_show_a_bowl():
    # Information criterion (BIC): a bowl under ripples pays for its 2d terms, ripples alone do not; fewer than two
    # designs a coefficient never carry it.
    rng = np.random.default_rng(13)
    X = rng.random((40, 2))
    ripples = np.sin(6 * np.pi * X[:, 0]) * np.cos(6 * np.pi * X[:, 1])
    bowl = 8.0 * np.sum((X - 0.4) ** 2, axis=1)
    theta = np.array([np.log(0.1), np.log(0.1), 0.0, np.log(1e-6)])
    assert GaussianProcess(X, bowl + ripples, theta).trend.quadratic
    assert not GaussianProcess(X, ripples, theta).trend.quadratic
    assert not GaussianProcess(X[:9], bowl[:9], theta).trend.quadratic  # 9 < 2 (2d + 1)


def test_a_probe_off_a_bound_slides_along_the_constraint_active_there():
    from mechopt.optimize.auto.polish import nearest_feasible

    # Closed form: at the vertex (0, 0) of the bound u0 >= 0 and the constraint u1 - u0 >= 0, a probe moved to
    # u0 = 0.1 and held on the constraint is (0.1, 0.1); without holding it, (0.1, 0.1) is also the nearest feasible
    # design to (0.1, 0); from (0, 0.5) off the constraint, (0.1, 0.5) is feasible and kept.
    margins = lambda U: (U[:, 1] - U[:, 0])[:, None]  # noqa: E731
    np.testing.assert_allclose(nearest_feasible(np.array([0.1, 0.0]), 0, margins, np.array([0]), np.zeros(2)),
                               [0.1, 0.1], atol=1e-7)
    np.testing.assert_allclose(nearest_feasible(np.array([0.1, 0.0]), 0, margins), [0.1, 0.1], atol=1e-7)
    np.testing.assert_allclose(nearest_feasible(np.array([0.1, 0.5]), 0, margins), [0.1, 0.5], atol=1e-9)


def test_the_ventilator_at_20_leaves_the_vertex_of_the_toggle_margin_and_bc_lower_bound():
    # Seeds 0, 5, 6 and 9 of 10 ended at the vertex (30, 68.35, 250) mm, T_RMS 1.76373 N·m (+0.31 %): the bound
    # probe moved |BC| off its bound and off the toggle margin.  Sliding along the margin, a run leaves the vertex:
    # seed 5 (since the global fit's white-noise floor; seed 6 before it) ends at 1.75880 N·m, +0.034 %, and at the
    # vertex with the slide switched off (an ad hoc check).
    from mechopt.studies.catalogue import load_study

    problem = load_study("ventilator", {"engine": "analytic"}).problem
    r = minimize(problem, 20, method="auto", seed=5)
    assert r.fun == pytest.approx(1.7582, rel=1e-3)


def test_inverse_from_the_cholesky_factor_is_the_inverse():
    from mechopt.optimize.auto.gp import _inverse

    rng = np.random.default_rng(4)
    B = rng.standard_normal((40, 40))
    K = B @ B.T + 1e-3 * np.eye(40)
    Kinv = _inverse(np.linalg.cholesky(K))
    np.testing.assert_array_equal(Kinv, Kinv.T)
    np.testing.assert_allclose(Kinv @ K, np.eye(40), atol=1e-8)


def test_additive_kernel_matches_its_closed_form_inside_and_far_outside_the_cube():
    from mechopt.optimize.auto.additive_kernel import additive_gradient, additive_gram, additive_matern

    def direct(U, V, ell):
        S = np.sqrt(5.0) * np.abs(U[:, None, :] - V[None, :, :]) / ell
        E = np.exp(-S)
        return np.sum((1.0 + S + S * S / 3.0) * E, axis=2), np.moveaxis(S * S / 3.0 * (1.0 + S) * E, 2, 0)

    rng = np.random.default_rng(2)
    X, ell = rng.random((12, 3)), np.array([0.3, 0.05, 2.0])
    # Far outside the unit cube with a length-scale at its lower bound the per-design exponentials would overflow.
    U = np.vstack([rng.random((5, 3)), [[3.0, -2.0, 0.5]]])
    for ell_used in (ell, np.array([0.3, 5e-3, 2.0])):
        np.testing.assert_allclose(additive_matern(U, X, ell_used), direct(U, X, ell_used)[0], rtol=1e-12, atol=1e-14)
    K, G = direct(X, X, ell)
    np.testing.assert_allclose(additive_gram(X, ell), K, rtol=1e-12)
    W = rng.standard_normal((12, 12))
    W = W + W.T
    np.testing.assert_allclose(additive_gradient(X, ell, W), np.einsum("ij,kij->k", W, G), rtol=1e-10)


def test_a_fit_that_sees_white_noise_is_refitted_at_the_designs_spacing():
    # Eight Sobol designs of cosine_bowl3 look uncorrelated to the marginal likelihood, which puts every
    # length-scale on its lower bound: a model of white noise, flat expected improvement.  With the floor the fit
    # is redone with no length-scale below half the designs' median nearest-neighbour distance.
    X = qmc.Sobol(3, seed=7).random(8)
    y = standardise(SUITE["cosine_bowl3"]().function(X), compress_tail=False)
    plain = fit_gp(X, y, np.random.default_rng(0), prior=False)
    assert np.allclose(np.exp(plain.theta[:3]), 5e-3) and _sees_no_neighbour(plain)
    floored = fit_gp(X, y, np.random.default_rng(0), prior=False, spacing_floor=True)
    assert np.all(np.exp(floored.theta[:3]) >= 0.5 * _median_spacing(X) * (1 - 1e-9))
    assert not _sees_no_neighbour(floored)
    # The median spacing of the designs, by hand for three of them on a line.
    assert _median_spacing(np.array([[0.0, 0.0], [0.1, 0.0], [0.4, 0.0]])) == pytest.approx(0.1)


def test_a_fit_that_sees_its_neighbours_is_left_alone_by_the_floor():
    rng = np.random.default_rng(4)
    X = rng.random((20, 2))
    y = (X[:, 0] - 0.3) ** 2 + np.sin(4.0 * X[:, 1])
    y = (y - y.mean()) / y.std()
    plain = fit_gp(X, y, np.random.default_rng(0), prior=False)
    assert not _sees_no_neighbour(plain)
    floored = fit_gp(X, y, np.random.default_rng(0), prior=False, spacing_floor=True)
    np.testing.assert_array_equal(floored.theta, plain.theta)
