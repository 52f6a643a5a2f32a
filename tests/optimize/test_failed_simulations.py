"""Failed simulations are a hidden constraint for every mechopt method, never the end of a run (issue 22)."""

import pytest

import mechopt
from mechopt.studies.benchmark_functions import SUITE


@pytest.mark.parametrize("method", ["auto", "sparse", "sparse-global"])
def test_no_method_raises_where_the_simulator_fails_and_each_finds_the_minimum(method):
    # Hartmann-3 whose simulator raises where x0 > 0.85 and returns NaN where x1 > 0.9 (its minimum is inside).
    problem = SUITE["failing_hartmann3"]()
    result = mechopt.minimize(problem, budget=100, method=method, seed=0)
    assert result.success and result.nfev <= 100
    assert result["nfailed"] > 0  # the runs did meet the failure region
    gap = 100 * (result.fun - problem.f_min) / problem.f_range
    assert gap < 0.5  # measured: auto 0.0006 %, sparse 0.0001 % (the line model handed over), sparse-global 0.017 %


def test_the_line_model_hands_over_when_failures_leave_too_few_lines():
    problem = SUITE["failing_hartmann3"]()
    result = mechopt.minimize(problem, budget=100, method="sparse", seed=0)
    assert "the line model could not be built" in result.message and "plan global" in result.message


def test_a_run_whose_every_simulation_fails_says_why():
    # An evaluate that returns a number instead of its outputs: every design fails the same way, and the result
    # names the reason, not only the count; each failed design is listed with its reason.
    import mechopt

    class Wrong(mechopt.DesignProblem):
        name = "wrong"
        variables = (mechopt.Variable("a", 5.0, 40.0, "mm"), mechopt.Variable("b", 5.0, 40.0, "mm"))
        outputs = ("f",)
        objective = "f"

        def evaluate(self, x):
            return float(x[0])

    r = mechopt.minimize(Wrong(), 10, seed=0, stop_after_failures=0)
    assert not r.success and r.nfailed == 10 == len(r.failures)
    assert "the first with: evaluate returned float, expected a dict with outputs ['f']" in r.message
    assert all(5.0 <= x[0] <= 40.0 and "evaluate returned float" in why for x, why in r.failures)


def test_an_infinite_objective_fails_like_nan_and_the_model_still_learns():
    # +inf where x0 > 0.5 (an objective that rejects a design by itself): it counts as a failure, and the model's
    # targets stay finite; the NaN targets it once made left the model blind (0.104 with 17 failures, measured).
    import numpy as np

    from mechopt.optimize.auto.search import auto_search

    def f(X):
        return np.where(X[:, 0] > 0.5, np.inf, np.sum(X * X, axis=1))

    r = auto_search(f, np.array([[0.0, 1.0]] * 3), 30, seed=0)
    assert r.nfev == 30 and r.nfailed == int(np.sum(~np.isfinite(r.values)))
    assert r.fun < 1e-3  # measured 0 (the minimum at the origin, a vertex), 5 failed


def test_a_simulator_failing_in_most_of_the_box_gets_the_model_as_soon_as_two_succeed():
    # Successes only where x0 >= 0.9 (a tenth of the box): the first Sobol design finds few, and the rest of the
    # budget went to more Sobol designs (26 of 30 failed, best 1.03); after two successes the model steers.
    import numpy as np

    from mechopt.optimize.auto.search import auto_search

    def f(X):
        return np.where(X[:, 0] < 0.9, np.nan, np.sum(X * X, axis=1))

    r = auto_search(f, np.array([[0.0, 1.0]] * 3), 30, seed=0)
    assert r.nfev == 30
    assert r.nfailed <= 20  # measured 13
    assert r.fun < 0.9  # the minimum 0.81 at (0.9, 0, 0); measured 0.824


def test_sparse_global_learns_where_the_simulator_fails():
    # At 60 simulations the lines leave few successes; the steps on the corrected model, fitted to those only,
    # went on into the failing region: 22, 53, 54, 54 and 53 of 60 failed in seeds 0-4, median gap 4.1 %.
    import numpy as np

    problem = SUITE["failing_hartmann3"]()
    failed, gaps = [], []
    for seed in range(5):
        result = mechopt.minimize(problem, budget=60, method="sparse-global", seed=seed)
        assert result.nfev == 60
        failed.append(result.nfailed)
        gaps.append(100 * (result.fun - problem.f_min) / problem.f_range)
    assert max(failed) <= 25  # measured 10, 10, 17, 13, 10
    assert np.median(gaps) < 0.5  # measured 0.013 %


def _sporadic(X):
    """True at about 15 % of designs, scattered at random but fixed by the design (a solver that does not converge
    at some parameter values, with no region to learn)."""
    import numpy as np

    h = np.sin(X @ np.array([12.9898, 78.233, 37.719])[: X.shape[1]]) * 43758.5453
    return h - np.floor(h) < 0.15


def test_failures_scattered_among_successes_leave_the_landscape_as_it_is():
    # A failure used to enter the model at the worst value that succeeded: beside the optimum that is a spike the fit
    # followed with short length-scales (median gap 1.84 % over these 10 seeds, 2 runs within 0.01 %).  Now it enters
    # at the model's prediction plus its variance there: median 0.0087 %, 6 runs within 0.01 %.
    import numpy as np

    from mechopt.optimize.auto.search import auto_search
    from mechopt.studies.benchmark_functions import Hartmann3

    f = Hartmann3()

    def evaluate(X):
        return np.where(_sporadic(X), np.nan, f.function(X))

    gaps, failed = [], 0
    for seed in range(10):
        r = auto_search(evaluate, np.array([[0.0, 1.0]] * 3), 30, seed=seed)
        gaps.append(100 * (r.fun - f.f_min) / f.f_range)
        failed += r.nfailed
    assert failed >= 30  # the runs did meet failures (measured 54 of 300)
    assert np.median(gaps) < 0.1
