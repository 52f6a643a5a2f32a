"""On a noisy simulator the default method answers with the design of lowest model mean, not the luckiest value."""

import hashlib

import numpy as np

from mechopt.optimize.auto.answer import lowest_mean
from mechopt.optimize.auto.gp import fit_gp
from mechopt.optimize.auto.search import auto_search
from mechopt.optimize.auto.transform import standardise
from mechopt.studies.benchmark_functions import Hartmann3, NoisyHartmann6


def _hash_noise(X: np.ndarray) -> np.ndarray:
    """A simulator's numerical noise: deterministic in the design (a time step, a mesh), rough across designs."""
    seeds = [int.from_bytes(hashlib.sha256(np.round(x, 9).tobytes()).digest()[:8], "little") for x in X]
    return np.array([np.random.default_rng(s).standard_normal() for s in seeds])


def _noisy_hartmann3(relative_sd: float):
    f = Hartmann3()
    bounds = np.array([[v.lower, v.upper] for v in f.variables])
    return f, bounds, lambda X: f.function(np.atleast_2d(X)) + relative_sd * f.f_range * _hash_noise(np.atleast_2d(X))


def test_on_a_noisy_simulator_the_answer_is_closer_to_the_optimum_than_the_lowest_value_simulated():
    # Noise of 5 % of the range: the lowest of 30 values is mostly a lucky draw.  Measured, seeds 0-5, the
    # noise-free gap at the answer: median 0.79 % (the lowest value's design: 1.25 %); 5 runs said so (0.44 %, 0.95 %
    # and 4 before the GP's prior mean moved to optimize/auto/trend.py, which computes it to other last bits).
    f, bounds, evaluate = _noisy_hartmann3(0.05)
    answer, lowest, said = [], [], 0
    for seed in range(6):
        r = auto_search(evaluate, bounds, 30, seed=seed)
        gap = lambda x: 100 * (f.function(np.atleast_2d(x))[0] - f.f_min) / f.f_range  # noqa: E731
        answer.append(gap(r.x))
        lowest.append(gap(r.X[np.argmin(r.values)]))
        said += "looks noisy" in r.message
        assert r.fun == evaluate(r.x[None, :])[0]  # the answer's value is its simulation, not the model's
    assert np.median(answer) < 0.75 * np.median(lowest)
    assert said >= 3


def test_a_deterministic_simulator_keeps_its_lowest_value_as_the_answer():
    f = Hartmann3()
    bounds = np.array([[v.lower, v.upper] for v in f.variables])
    for seed in range(3):
        r = auto_search(lambda X: f.function(np.atleast_2d(X)), bounds, 25, seed=seed)
        assert r.fun == r.values.min() and "noisy" not in r.message


def test_lowest_mean_picks_the_smoothed_minimum_and_not_the_luckiest_draw():
    # A parabola with its minimum at 0.6, 40 designs, noise of sd 0.02 (values 0 to 0.36).  Measured, seeds 0-5:
    # the lowest value's design 0.04-0.14 from the minimum, the lowest mean's 0.007-0.044.
    for seed in range(6):
        rng = np.random.default_rng(seed)
        U = rng.random((40, 1))
        y = (U[:, 0] - 0.6) ** 2 + 0.02 * rng.standard_normal(40)
        gp = fit_gp(U, standardise(y), rng, starts=3, maxiter=100)
        best = int(np.argmin(y))
        i = lowest_mean(gp, U, np.arange(40), best, prior=False)
        assert abs(U[i, 0] - 0.6) < min(0.05, abs(U[best, 0] - 0.6))
        # With the noise at its floor the lowest value stands.
        gp.noise = 1e-10
        assert lowest_mean(gp, U, np.arange(40), best, prior=False) == best


def test_the_noisy_suite_function_repeats_itself_at_a_design_and_scatters_across_designs():
    p = NoisyHartmann6()
    X = np.random.default_rng(0).random((400, 6))
    noise = np.array([p.evaluate(x)["f"] for x in X]) - p(X)
    assert p.evaluate(X[0])["f"] == p.evaluate(X[0].copy())["f"]
    assert 0.9 * p.noise * p.f_range < noise.std() < 1.1 * p.noise * p.f_range
    assert abs(noise.mean()) < 0.2 * p.noise * p.f_range


def test_the_evidence_for_noise_is_strong_on_scattered_values_and_absent_on_a_smooth_function():
    from mechopt.optimize.auto.gp import noise_log_bayes_factor

    rng = np.random.default_rng(7)
    U = rng.random((30, 2))
    smooth = np.sin(3 * U[:, 0]) + np.cos(2 * U[:, 1])
    for y, strong in ((smooth, False), (smooth + 0.05 * rng.standard_normal(30), True)):
        gp = fit_gp(U, standardise(y), rng, starts=3, maxiter=100, prior=False)
        assert (noise_log_bayes_factor(gp, 30, prior=False, null_noise=1e-6) > 3.0) is strong


def test_minimize_on_the_noisy_suite_function_says_so_and_reports_the_answers_own_simulation():
    import mechopt

    p = NoisyHartmann6()
    r = mechopt.minimize(p, budget=60, seed=0)
    assert "looks noisy" in r.message
    assert r.fun == p.evaluate(np.asarray(r.x))["f"]  # the simulated value, noise included, not the model's
    # The answer is not the design of lowest simulated value, which the message quotes last.
    lowest = float(r.message.rsplit("(", 1)[1].rstrip(")"))
    assert r.fun > lowest
