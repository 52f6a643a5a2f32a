"""Distinct local minima of a gridded field (surrogate.basins)."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.surrogate import SurrogateError
from mechopt.surrogate.basins import field_minima, grid_local_minima, tensor_grid, thin


def _egg(X: np.ndarray) -> np.ndarray:
    # Two Gaussian wells, at (0.25, 0.25) (deeper) and (0.75, 0.75), in a bowl that rises towards the box's faces,
    # so no face carries a minimum of its own.
    def well(c):
        return np.exp(-40 * np.sum((X - c) ** 2, axis=1))
    return -well(np.array([0.25, 0.25])) - 0.9 * well(np.array([0.75, 0.75])) + np.sum((X - 0.5) ** 2, axis=1)


def test_finds_every_basin_best_first():
    found = field_minima(_egg, [0, 0], [1, 1], None, 81, radius=0.2)
    assert len(found) == 2
    np.testing.assert_allclose(found.x[0], [0.25, 0.25], atol=1 / 80)
    np.testing.assert_allclose(found.x[1], [0.75, 0.75], atol=1 / 80)
    assert found.value[0] < found.value[1]


def test_region_masks_points_and_edge_minima_count():
    # Outside x + y <= 1 the field does not exist: the basin at (0.75, 0.75) disappears, and the tilt's minimum on
    # the diagonal edge is a minimum of the region even though the field goes on decreasing beyond it.
    found = field_minima(lambda X: X[:, 0] + 2 * X[:, 1] - 3 * (X[:, 0] + X[:, 1]), [0, 0], [1, 1],
                         lambda X: X.sum(axis=1) <= 1 + 1e-12, 41, radius=0.1)
    assert len(found) >= 1
    assert found.x[0].sum() == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(found.x[0], [1.0, 0.0], atol=1e-9)


def test_thin_keeps_one_point_per_radius():
    x = np.array([[0.0, 0.0], [0.05, 0.0], [0.5, 0.0], [0.52, 0.0], [1.0, 1.0]])
    v = np.array([3.0, 1.0, 2.0, 0.5, np.nan])
    kept = thin(x, v, radius=0.1)
    np.testing.assert_allclose(kept.x, [[0.52, 0.0], [0.05, 0.0]])
    assert len(thin(x, v, radius=0.1, max_count=1)) == 1
    # Distances scaled by the box: radius 0.1 of a box 10 wide separates points 0.5 apart in x.
    assert len(thin(x * [10, 1], v, radius=0.1, scale=np.array([10.0, 1.0]))) == 2


def test_three_dimensional_grid_and_errors():
    axes, pts = tensor_grid([0, 0, 0], [1, 2, 3], 5)
    assert pts.shape == (125, 3) and axes[2][-1] == 3
    values = np.sum((pts - [0.5, 1.0, 1.5]) ** 2, axis=1).reshape(5, 5, 5)
    found = grid_local_minima(values, axes, radius=0.1)
    assert len(found) == 1
    np.testing.assert_allclose(found.x[0], [0.5, 1.0, 1.5])
    with pytest.raises(SurrogateError):
        grid_local_minima(values[:4], axes, radius=0.1)
    with pytest.raises(SurrogateError):
        tensor_grid([0, 0], [1, 0], 5)
