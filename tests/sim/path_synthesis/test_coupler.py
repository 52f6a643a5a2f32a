"""The coupler point of paper 000's slider-crank against an independent construction, its derivatives, branches."""

import numpy as np
import pytest
from scipy.optimize import brentq

from mechopt.sim.path_synthesis.coupler import coupler_point, coupler_point_derivatives, linkage_joints

TABLE2 = np.array([1.292, 3.277, 1.292, 3.875, 1.970, 3.090, 1.356, -0.583])


def _random_designs(n, seed):
    """Designs whose crank turns fully (a2 > a1 + |a5|), with every sign of a3, a4, a5."""
    rng = np.random.default_rng(seed)
    a1 = rng.uniform(0.2, 3.0, n)
    a5 = rng.uniform(-4.0, 4.0, n)
    a2 = a1 + np.abs(a5) + rng.uniform(0.05, 4.0, n)
    return np.column_stack([a1, a2, rng.uniform(-5, 5, n), rng.uniform(-5, 5, n), a5, rng.uniform(-np.pi, np.pi, n),
                            rng.uniform(-5, 5, n), rng.uniform(-5, 5, n)])


def _constructed(a, phi, branch):
    """P by geometry: the slider B where the circle of radius a2 about the crank pin A meets the line y' = a5 (a root
    found numerically on the branch's side of A), then a3 along A→B and a4 to its left, rotated by a6, shifted by
    (a8, a7)."""
    A = np.array([a[0] * np.cos(phi), a[0] * np.sin(phi)])

    def gap(s):
        return np.hypot(s - A[0], a[4] - A[1]) - a[1]

    if branch > 0:
        s = brentq(gap, A[0], A[0] + 2 * a[1] + 1.0, xtol=1e-15)
    else:
        s = brentq(gap, A[0] - 2 * a[1] - 1.0, A[0], xtol=1e-15)
    e = (np.array([s, a[4]]) - A) / a[1]
    p = A + a[2] * e + a[3] * np.array([-e[1], e[0]])
    c, sn = np.cos(a[5]), np.sin(a[5])
    return np.array([c * p[0] - sn * p[1] + a[7], sn * p[0] + c * p[1] + a[6]])


@pytest.mark.parametrize("branch", [1, -1])
def test_coupler_point_matches_the_loop_closure_solved_numerically(branch):
    for a in _random_designs(12, 1):
        for phi in np.linspace(0.1, 2 * np.pi, 7):
            x, y = coupler_point(a, phi, branch)
            np.testing.assert_allclose([x, y], _constructed(a, phi, branch), atol=1e-10)


def test_the_printed_eq8_with_its_stray_cos_phi_is_not_what_is_computed():
    a, phi = TABLE2, 1.0
    u = (a[4] - a[0] * np.sin(phi)) / a[1]
    c = -np.sqrt(1 - u * u)
    y_eq6 = (a[2] - a[1]) * u + a[4] + a[3] * c
    y_eq8 = (a[2] - a[1]) * u * np.cos(phi) + a[4] + a[3] * c
    x_local = a[0] * np.cos(phi) + a[2] * c - a[3] * u
    x, y = coupler_point(a, phi, -1)
    ca, sa = np.cos(a[5]), np.sin(a[5])
    assert x_local * sa + y_eq6 * ca + a[6] == pytest.approx(float(y), abs=1e-12)
    assert abs(x_local * sa + y_eq8 * ca + a[6] - float(y)) > 0.1


def test_branch_identity_a5_a6_k_phi():
    """(a5, a6, K, φ) and (−a5, a6 + π, −K, φ + π) are the same linkage: the same coupler point."""
    phi = np.linspace(0, 2 * np.pi, 50)
    for a in _random_designs(10, 2):
        b = a.copy()
        b[4], b[5] = -a[4], a[5] + np.pi
        for k in (1, -1):
            np.testing.assert_allclose(coupler_point(a, phi, k), coupler_point(b, phi + np.pi, -k), atol=1e-12)


def test_derivatives_match_finite_differences():
    h = 1e-6
    for a in _random_designs(6, 3):
        for k in (1, -1):
            for phi in (0.3, 2.0, 4.4):
                x, y, dx, dy, ddx, ddy = coupler_point_derivatives(a, k, phi)
                assert (x, y) == pytest.approx(tuple(map(float, coupler_point(a, phi, k))), abs=1e-12)
                p1, p0 = np.array(coupler_point(a, phi + h, k)), np.array(coupler_point(a, phi - h, k))
                np.testing.assert_allclose([dx, dy], (p1 - p0) / (2 * h), rtol=1e-6, atol=1e-7)
                d1 = np.array(coupler_point_derivatives(a, k, phi + h)[2:4])
                d0 = np.array(coupler_point_derivatives(a, k, phi - h)[2:4])
                np.testing.assert_allclose([ddx, ddy], (d1 - d0) / (2 * h), rtol=1e-5, atol=1e-6)


def test_linkage_joints_close_the_loop():
    a = TABLE2
    phi = np.linspace(0, 2 * np.pi, 9)
    j = linkage_joints(a, phi, -1)
    np.testing.assert_allclose(np.linalg.norm(j["A"] - j["O"], axis=-1), a[0], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(j["B"] - j["A"], axis=-1), a[1], atol=1e-12)
    np.testing.assert_allclose(j["P"], np.stack(coupler_point(a, phi, -1), axis=-1), atol=1e-12)
    # B stays on the slider line: its distance to the line through the two points given is zero
    p, q = j["slider_line"]
    t = (q - p) / np.linalg.norm(q - p)
    off = (j["B"] - p) @ np.array([-t[1], t[0]])
    np.testing.assert_allclose(off, 0.0, atol=1e-12)
