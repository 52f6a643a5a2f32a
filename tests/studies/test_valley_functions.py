"""The valleys (studies.valley_functions): known answers of the BBOB definitions, rotations, shifts, registration."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import rosen

from mechopt.studies.benchmark_functions import SUITE
from mechopt.studies.valley_functions import VALLEYS, Valley


@pytest.mark.parametrize("name", sorted(VALLEYS))
def test_zero_at_the_shift_only_and_orthogonal_rotations(name):
    p = VALLEYS[name]()
    d = p.dim
    assert d in (3, 6, 10) and SUITE[name] is VALLEYS[name]
    for Q in (p.rotation, p.second_rotation):
        np.testing.assert_allclose(Q @ Q.T, np.eye(d), atol=1e-12)
    # The shift is inside the box (in BBOB's [−4, 4]^d) and off the centre.
    assert np.all(np.abs(p.shift) <= 4.0) and np.linalg.norm(p.shift) > 0.5
    np.testing.assert_array_equal(p.x_min, p.shift[None, :])
    assert p(p.x_min)[0] == 0.0 == p.f_min
    X = np.random.default_rng(0).uniform(-5.0, 5.0, (200, d))
    assert np.all(p(X) > 0.0)
    # Drawn from a seed of the name: every instance is the same valley, and valleys differ from each other.
    np.testing.assert_array_equal(VALLEYS[name]().rotation, p.rotation)


def test_seeds_differ_per_function_and_dimension():
    shifts = [cls.shift[:3] for cls in VALLEYS.values()]
    assert len({tuple(np.round(s, 9)) for s in shifts}) == len(shifts)


def _design(p: Valley, z: np.ndarray) -> np.ndarray:
    """The design x whose R (x − x*) is z."""
    return (p.shift + p.rotation.T @ z)[None, :]


@pytest.mark.parametrize("d", [3, 6, 10])
def test_ellipsoid_condition_and_different_powers_along_the_rotated_axes(d):
    ell, powers = SUITE[f"valley_ellipsoid{d}"](), SUITE[f"valley_different_powers{d}"]()
    values = [float(ell(_design(ell, 0.5 * np.eye(d)[i]))[0]) for i in range(d)]
    # 0.25 · 10^(6 (i−1)/(d−1)): 0.25 along the first axis, 0.25e6 along the last, condition 10^6.
    np.testing.assert_allclose(values, 0.25 * np.logspace(0, 6, d), rtol=1e-9)
    # |t|^(2 + 4 (i−1)/(d−1)) under the root: 0.5^1 on the first axis, 0.5^3 on the last.
    assert float(powers(_design(powers, 0.5 * np.eye(d)[0]))[0]) == pytest.approx(0.5, rel=1e-9)
    assert float(powers(_design(powers, -0.5 * np.eye(d)[-1]))[0]) == pytest.approx(0.125, rel=1e-9)


@pytest.mark.parametrize("d", [3, 6, 10])
def test_rosenbrock_is_scipys_in_the_rotated_coordinates(d):
    p = SUITE[f"valley_rosenbrock{d}"]()
    z = np.random.default_rng(d).uniform(-1.0, 2.0, d)
    # z = R (x − x*) + 1 (the scale max(1, √d/8) is 1 up to d = 64).
    assert float(p(_design(p, z - 1.0))[0]) == pytest.approx(float(rosen(z)), rel=1e-10)


@pytest.mark.parametrize("d", [3, 6, 10])
def test_bent_cigar_and_sharp_ridge_known_values(d):
    cigar, ridge = SUITE[f"valley_bent_cigar{d}"](), SUITE[f"valley_sharp_ridge{d}"]()
    # With every component of R (x − x*) negative T_asy is the identity: z = R R (x − x*).
    z = -np.abs(np.random.default_rng(d).uniform(0.1, 1.0, d))
    w = cigar.rotation @ z
    assert float(cigar(_design(cigar, z))[0]) == pytest.approx(w[0] ** 2 + 1e6 * np.sum(w[1:] ** 2), rel=1e-10)
    # A positive component is bent: x^(1 + 0.5 (i−1)/(d−1) √x); on the first axis the exponent is 1.
    z_last = np.zeros(d)
    z_last[-1] = 4.0
    w = cigar.rotation @ np.r_[np.zeros(d - 1), 4.0 ** 2.0]
    assert float(cigar(_design(cigar, z_last))[0]) == pytest.approx(w[0] ** 2 + 1e6 * np.sum(w[1:] ** 2), rel=1e-10)
    # Along the ridge's first axis (Q Λ^10 R (x − x*) = t e_1) the ridge is t²; off it, 100 × the distance.
    lam = 10.0 ** (0.5 * np.arange(d) / (d - 1))
    for w, expected in ((0.3 * np.eye(d)[0], 0.09), (0.3 * np.eye(d)[1], 30.0)):
        z = (ridge.second_rotation.T @ w) / lam
        assert float(ridge(_design(ridge, z))[0]) == pytest.approx(expected, rel=1e-9)
