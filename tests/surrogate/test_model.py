"""The blended sparse exponential model: interpolation, exact reproduction of its class, convergence, I/O."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.surrogate import LinePlan, SparseExponentialModel, SurrogateError, SurrogateWarning

PAPER_DELTA = np.array([0.000, 0.920, 0.503])
PAPER_ORIGIN = np.array([31.000, 257.859, 72.705])
NODES7 = np.array([[0, 0], [10, 0], [5, 8], [-5, 8], [-10, 0], [-5, -8], [3, -4.0]])
# Shared exponents (per sample step): two real ones and a damped oscillation.
LAMBDAS = np.array([-0.05, 0.02, -0.01 + 0.03j, -0.01 - 0.03j])


def class_plan() -> LinePlan:
    """Seven lines along the paper's Δ; offsets have components along Δ too (they only shift k)."""
    E = LinePlan(PAPER_DELTA, PAPER_ORIGIN, np.zeros((1, 3))).normal_basis
    along = np.array([0.0, 0.37, -1.1, 2.0, 0.0, -0.5, 3.3])[:, None] * PAPER_DELTA
    return LinePlan(PAPER_DELTA, PAPER_ORIGIN, NODES7 @ E + along)


def class_coefficients(P):
    """Coefficients quadratic in (p, q): inside the blend's space for 7 nodes (complete degree 2)."""
    p, q = P[:, 0], P[:, 1]
    c = 0.2 + 0.01 * p
    return np.stack([1 + 0.1 * p + 0.02 * q * q, 0.5 - 0.003 * p * q + 0.01 * q, c * (1 + 0.5j), c * (1 - 0.5j)], 1)


def class_function(plan):
    def T(X):
        P, d = plan.coordinates(X)
        return (class_coefficients(P) * np.exp(np.outer(d, LAMBDAS))).sum(axis=1).real

    return T


def sample(plan, T, ks, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    out = []
    for i in range(plan.n_lines):
        v = T(plan.points(i, ks))
        out.append((ks, v * (1 + noise * rng.standard_normal(ks.size))))
    return out


def random_hull_points(model, n, seed):
    ends = model.plan.segment_ends()
    w = np.random.default_rng(seed).dirichlet(np.full(len(ends), 0.5), n)
    return w @ ends


@pytest.mark.parametrize("method,solver", [("matrix_pencil", "ls"), ("esprit", "tls")])
def test_reproduces_samples_and_its_model_class(method, solver):
    plan = class_plan()
    T = class_function(plan)
    ks = np.arange(-3, 40)
    data = sample(plan, T, ks)
    model = SparseExponentialModel(method=method, solver=solver, extrapolation="exponential").fit(plan, data)
    assert model.l == 7 and model.orders == [4, 4, 4, 4, 3, 4, 4]  # c_0 vanishes at node (−10, 0)
    # Every sample to 1e-9 relative.
    for i, (k, v) in enumerate(data):
        assert np.max(np.abs(model.predict(plan.points(i, k)) - v)) <= 1e-9 * np.max(np.abs(v))
    # Exactly (1e-9 relative) at random points of the hull: T is in the model class.
    X = random_hull_points(model, 3000, seed=1)
    assert model.contains(X).all()
    assert np.max(np.abs(model.predict(X) - T(X))) <= 1e-9 * np.max(np.abs(T(X)))


def test_restriction_to_a_line_is_that_lines_fit_even_with_noise():
    plan = class_plan()
    ks = np.arange(0, 50)
    model = SparseExponentialModel().fit(plan, sample(plan, class_function(plan), ks, noise=1e-4))
    kk = np.linspace(0, 49, 101)
    for i, fit in enumerate(model.fits):
        assert np.allclose(model.predict(plan.points(i, kk)), fit(kk), rtol=1e-9, atol=0)


def test_terms_are_inspectable():
    plan = class_plan()
    model = SparseExponentialModel(extrapolation="exponential").fit(
        plan, sample(plan, class_function(plan), np.arange(5, 40))
    )
    d = np.linspace(-5.0, 50.0, 23)
    # f_i(d) = Re Σ α_j exp(λ_j d) with the published coefficients and exponents (Eq. 15 shift included).
    rebuilt = np.stack(
        [(np.exp(np.outer(d, lam)) @ a).real for lam, a in zip(model.exponents, model.coefficients, strict=True)], 1
    )
    assert np.allclose(rebuilt, model.line_values(d), rtol=1e-9, atol=1e-12)
    assert model.n_terms == sum(model.orders)
    for lam in model.exponents:
        for true in LAMBDAS:
            if np.min(np.abs(lam - true)) > 1e-7:
                # Line 4 lacks the first term; every other exponent must be found.
                assert np.isclose(true, LAMBDAS[0])


def test_linear_continuation_beyond_a_lines_samples():
    # Default guard: beyond its samples a line's model continues along its end tangent (C1), inside it is unchanged.
    plan = class_plan()
    data = sample(plan, class_function(plan), np.arange(5, 40))
    pure = SparseExponentialModel(extrapolation="exponential").fit(plan, data)
    guarded = SparseExponentialModel().fit(plan, data)
    inside = np.linspace(0.0, 34.0, 35) + guarded.shifts[0]
    np.testing.assert_allclose(guarded.line_values(inside)[:, 0], pure.line_values(inside)[:, 0], rtol=1e-12)
    end = guarded.shifts[0] + 34.0
    beyond = end + np.array([1.0, 5.0, 20.0])
    slope = pure.line_derivatives([end])[0, 0]
    np.testing.assert_allclose(guarded.line_values(beyond)[:, 0],
                               pure.line_values([end])[0, 0] + slope * (beyond - end), rtol=1e-12)
    np.testing.assert_allclose(guarded.line_derivatives(beyond)[:, 0], slope, rtol=1e-12)


def test_gradient_matches_finite_differences():
    plan = class_plan()
    model = SparseExponentialModel().fit(plan, sample(plan, class_function(plan), np.arange(40)))
    X = random_hull_points(model, 10, seed=2)
    h = 1e-5
    fd = np.column_stack([(model.predict(X + h * e) - model.predict(X - h * e)) / (2 * h) for e in np.eye(3)])
    assert np.max(np.abs(model.gradient(X) - fd)) <= 1e-7 * np.max(np.abs(fd))
    assert model.gradient(X[0]).shape == (3,) and isinstance(model.predict(X[0]), float)


def test_save_and_load_round_trip(tmp_path):
    plan = class_plan()
    model = SparseExponentialModel(order=[4, 4, 4, 4, 3, 4, 4]).fit(
        plan, sample(plan, class_function(plan), np.arange(40))
    )
    path = tmp_path / "model.json"
    model.save(path)
    again = SparseExponentialModel.load(path)
    X = random_hull_points(model, 100, seed=3)
    assert np.array_equal(again.predict(X), model.predict(X))
    assert again.orders == model.orders and again.order == model.order


def test_forced_order_that_fits_noise_warns_with_the_line_number():
    # With 1e-4 noise the slow oscillation is not resolvable on 40 samples (automatic orders are 3); forcing
    # order 4 makes the spare term fit noise at the Nyquist frequency, which must be reported.
    plan = class_plan()
    data = sample(plan, class_function(plan), np.arange(40), noise=1e-4)
    with pytest.warns(SurrogateWarning, match=r"line \d: exponential fit of order 4: negative real node"):
        SparseExponentialModel(order=4).fit(plan, data)


def _lattice(g):
    """Principal lattice of degree g on a triangle: unisolvent for the polynomials of degree g."""
    A, B, C = np.array([0.0, 0.0]), np.array([12.0, 0.0]), np.array([4.0, 10.0])
    return np.array([(i * A + j * B + (g - i - j) * C) / g for i in range(g + 1) for j in range(g + 1 - i)])


def test_held_out_error_falls_as_lines_and_samples_are_added():
    def f(X):  # smooth, not an exponential sum in d, coefficients not polynomial in (p, q)
        x, y, z = X.T
        return (2 + 0.3 * np.sin(0.25 * x + 0.1 * y)) * np.exp(-0.03 * z) + 0.5 * np.cos(0.15 * y - 0.05 * x) / (
            1 + 0.002 * (z + 0.5 * x) ** 2
        )

    delta, origin = np.array([0.1, -0.05, 0.6]), np.array([1.0, 2.0, 3.0])
    E = LinePlan(delta, origin, np.zeros((1, 3))).normal_basis
    errors = []
    X = None
    for g, n_samples in [(1, 30), (2, 40), (3, 50)]:
        # Same hull each time (triangle prism), more lines and more samples per line.
        plan = LinePlan(delta * 30 / n_samples, origin, _lattice(g) @ E)
        ks = np.arange(n_samples)
        model = SparseExponentialModel().fit(plan, sample(plan, f, ks, noise=1e-5, seed=g))
        if X is None:
            X = random_hull_points(model, 4000, seed=4)
        assert model.contains(X).all()
        errors.append(np.max(np.abs(model.predict(X) - f(X))) / np.max(np.abs(f(X))))
    # Observed roughly 5e-2, 2.4e-2, 2.5e-3: demand a clear decrease at each step.
    assert errors[1] < 0.7 * errors[0] and errors[2] < 0.3 * errors[1], errors


def test_bad_input_raises_one_line_errors():
    plan = class_plan()
    T = class_function(plan)
    good = sample(plan, T, np.arange(20))
    cases = [
        (lambda: SparseExponentialModel().fit(plan, good[:6]), r"7 lines but 6 sample sets"),
        (
            lambda: SparseExponentialModel().fit(plan, [(np.array([0, 1, 3, 4]), np.ones(4))] + good[1:]),
            r"line 0: sample indices must be consecutive integers, found a jump from k = 1 to 3",
        ),
        (
            lambda: SparseExponentialModel().fit(
                plan, good[:2] + [(np.arange(20), np.r_[np.ones(19), np.nan])] + good[3:]
            ),
            r"line 2: sample at k = 19 is nan",
        ),
        (lambda: SparseExponentialModel(order=11).fit(plan, good), r"line 0: order n = 11 needs at least 2n = 22"),
        (lambda: SparseExponentialModel(order=[3, 3]).fit(plan, good), r"one value per line"),
        (lambda: SparseExponentialModel(method="prony"), r"method must be one of"),
        (lambda: SparseExponentialModel().predict(np.zeros(3)), r"not fitted"),
        (lambda: SparseExponentialModel().fit(plan, good).predict(np.zeros((2, 2))), r"shape \(n, 3\)"),
    ]
    collinear = LinePlan(PAPER_DELTA, PAPER_ORIGIN, [[1, 0, 0], [2, 0, 0], [3, 0, 0]])
    cases.append((lambda: SparseExponentialModel().fit(collinear, good[:3]), r"collinear"))
    for call, pattern in cases:
        with pytest.raises(SurrogateError, match=pattern) as info:
            call()
        assert "\n" not in str(info.value)
