"""Closest points, the error E of Eq. 11 and its residuals: against brute force and the paper's Tables 2 and 3."""

import time

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from mechopt.sim.path_synthesis.closest_point import closest_points
from mechopt.sim.path_synthesis.coupler import coupler_point
from mechopt.sim.path_synthesis.path_error import fit_path
from mechopt.sim.path_synthesis.points import read_points
from mechopt.studies.study_file import PACKAGED_STUDIES

POINTS1 = read_points(PACKAGED_STUDIES / "path_synthesis_1" / "example1_points.csv")
POINTS2 = read_points(PACKAGED_STUDIES / "path_synthesis_2" / "example2_points.csv")
TABLE2 = np.array([1.292, 3.277, 1.292, 3.875, 1.970, 3.090, 1.356, -0.583])
TABLE2_PHI = np.array([4.877, 4.568, 4.409, 4.267, 4.104, 3.905, 3.579, 3.192, 2.992, 2.804, 2.634, 2.476, 2.323,
                       2.171, 2.014, 1.846])
TABLE3 = np.array([2.309, 48.819, -3.304, 24.498, 46.315, 4.726, -18.02, 15.293])
TABLE3_PHI = np.array([4.703, 4.92, 5.041, 5.181, 5.362, 5.528, 5.745, 5.875, -0.237, 0.049, 0.672, 1.331, 1.698,
                       1.996, 2.281, 2.494, 2.715, 2.933, 3.17, 3.483, 3.762, 3.752, 4.091, 4.265, 4.451])


def _brute_force(a, points, k):
    """Squared distances by a 200 000-angle grid, each polished by a bounded scalar minimisation."""
    grid = np.linspace(0, 2 * np.pi, 200_000, endpoint=False)
    x, y = coupler_point(a, grid, k)
    out = []
    for px, py in points:
        j = int(np.argmin((x - px) ** 2 + (y - py) ** 2))

        def d2(p, px=px, py=py):
            cx, cy = coupler_point(a, p, k)
            return float((cx - px) ** 2 + (cy - py) ** 2)

        r = minimize_scalar(d2, bounds=(grid[j] - 1e-4, grid[j] + 1e-4), method="bounded",
                            options={"xatol": 1e-13})
        out.append(min(r.fun, d2(grid[j])))
    return np.array(out)


@pytest.mark.parametrize(("design", "points"), [(TABLE2, POINTS1), (TABLE3, POINTS2)])
def test_closest_points_agree_with_brute_force(design, points):
    for k in (1, -1):
        phi, d2, _ = closest_points(design, points, k)
        ref = _brute_force(design, points, k)
        np.testing.assert_allclose(np.sqrt(d2), np.sqrt(ref), atol=1e-9)
        x, y = coupler_point(design, phi, k)
        np.testing.assert_allclose((x - points[:, 0]) ** 2 + (y - points[:, 1]) ** 2, d2, rtol=1e-12, atol=1e-15)


def test_closest_points_of_random_designs_are_stationary_and_no_worse_than_a_fine_grid():
    rng = np.random.default_rng(5)
    grid = np.linspace(0, 2 * np.pi, 20_000, endpoint=False)
    for _ in range(20):
        a1, a5 = rng.uniform(0.2, 3), rng.uniform(-3, 3)
        a = np.array([a1, a1 + abs(a5) + rng.uniform(0.01, 3), *rng.uniform(-4, 4, 2), a5,
                      *rng.uniform(-3, 3, 3)])
        pts = rng.uniform(-6, 6, (10, 2))
        for k in (1, -1):
            _, d2, _ = closest_points(a, pts, k)
            x, y = coupler_point(a, grid, k)
            coarse = ((x[None] - pts[:, :1]) ** 2 + (y[None] - pts[:, 1:]) ** 2).min(axis=1)
            assert np.all(d2 <= coarse + 1e-12)


def test_table2_gives_the_papers_error_on_branch_minus_one():
    f = fit_path(TABLE2, POINTS1)
    assert f.E == pytest.approx(0.0073, rel=0.02)
    assert f.E == pytest.approx(0.0073002, rel=1e-4)
    assert f.branch == -1 and f.E_other > 90.0
    # the printed inputs are the closest points' angles to 3 decimals
    np.testing.assert_allclose(f.phi, TABLE2_PHI, atol=2.5e-3)
    x, y = coupler_point(TABLE2, TABLE2_PHI, -1)
    assert np.sum((x - POINTS1[:, 0]) ** 2 + (y - POINTS1[:, 1]) ** 2) == pytest.approx(0.007311, rel=1e-3)


def test_table3_gives_the_papers_error_on_branch_minus_one():
    f = fit_path(TABLE3, POINTS2)
    assert f.E == pytest.approx(0.1037, rel=0.02)
    assert f.E == pytest.approx(0.103698, rel=1e-4)
    assert f.branch == -1
    x, y = coupler_point(TABLE3, TABLE3_PHI, -1)
    assert np.sum((x - POINTS2[:, 0]) ** 2 + (y - POINTS2[:, 1]) ** 2) == pytest.approx(0.10443, rel=1e-3)
    # a6 = 4.726 and 4.726 − 2π are the same linkage
    b = TABLE3.copy()
    b[5] -= 2 * np.pi
    assert fit_path(b, POINTS2).E == pytest.approx(f.E, rel=1e-12)


def test_residuals_square_to_e_and_the_branch_identity_keeps_e():
    f = fit_path(TABLE2, POINTS1)
    assert np.sum(f.residuals**2) == pytest.approx(f.E, rel=1e-13)
    b = TABLE2.copy()
    b[4], b[5] = -b[4], b[5] + np.pi
    g = fit_path(b, POINTS1)
    assert g.branch == -f.branch and g.E == pytest.approx(f.E, rel=1e-9)
    np.testing.assert_allclose(g.residuals, f.residuals, atol=1e-9)
    np.testing.assert_allclose(np.angle(np.exp(1j * (g.phi - f.phi - np.pi))), 0.0, atol=1e-7)


def test_one_simulation_costs_well_under_a_millisecond():
    fit_path(TABLE3, POINTS2)
    times = []
    for _ in range(200):
        t = time.perf_counter()
        fit_path(TABLE3, POINTS2)
        times.append(time.perf_counter() - t)
    assert np.median(times) < 1e-3


def test_residual_jacobian_matches_central_differences():
    from mechopt.sim.path_synthesis.jacobian import residual_jacobian

    for design, points in ((TABLE2, POINTS1), (TABLE3, POINTS2)):
        f = fit_path(design, points)
        J = residual_jacobian(design, f)
        h = 1e-6
        numeric = np.column_stack([
            (fit_path(design + h * e, points, branches=(f.branch,)).residuals
             - fit_path(design - h * e, points, branches=(f.branch,)).residuals) / (2 * h) for e in np.eye(8)])
        np.testing.assert_allclose(J, numeric, atol=1e-6 * np.abs(J).max())
