"""The continuous variables polished with the discrete ones held, against closed forms and the coil spring's best
known design."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mechopt import minimize
from mechopt.optimize.auto.design_grid import DesignGrid
from mechopt.optimize.auto.held_polish import held_maximise, polished_neighbours
from mechopt.studies.mixed_variable_functions import CoilSpring, PressureVessel

LO, HI = np.zeros(2), np.ones(2)


def _margin(U: np.ndarray) -> np.ndarray:
    """u1 + u0² − 1/2 >= 0: at u0 held, the least u1 is 1/2 − u0²."""
    return (U[:, 1] + U[:, 0] ** 2 - 0.5)[:, None]


def test_held_coordinate_kept_and_free_one_lands_on_the_constraint() -> None:
    x = held_maximise(lambda U: -U[:, 1], np.array([0.3, 0.9]), LO, HI, np.array([False, True]), _margin)
    assert x[0] == 0.3
    assert x[1] == pytest.approx(0.5 - 0.09, abs=1e-6)
    assert _margin(x[None, :])[0, 0] >= 0.0


def test_unconstrained_polish_finds_the_interior_maximum() -> None:
    x = held_maximise(lambda U: -(U[:, 1] - 0.7) ** 2, np.array([0.25, 0.1]), LO, HI, np.array([False, True]))
    assert x[0] == 0.25
    assert x[1] == pytest.approx(0.7, abs=1e-4)


def test_no_free_coordinate_returns_the_design() -> None:
    x = np.array([0.2, 0.4])
    assert np.array_equal(held_maximise(lambda U: U[:, 0], x, LO, HI, np.zeros(2, dtype=bool)), x)


def test_each_neighbour_gets_its_own_continuous_optimum() -> None:
    # u0 on the grid {0, 0.25, ..., 1}: the neighbours of 0.4 are 0.25 and 0.5 (radius 1, nearest 0.5), each
    # polished onto its own point of the constraint, which a rounding that keeps u1 misses.
    grid = DesignGrid([0.0, 0.0], [1.0, 1.0], [np.linspace(0.0, 1.0, 5), None])
    N = polished_neighbours(lambda U: -U[:, 1], grid, np.array([[0.4, 0.34]]), LO, HI, 1, _margin)
    for u0 in (0.25, 0.5, 0.75):
        polished = N[np.isclose(N[:, 0], u0) & (_margin(N)[:, 0] >= 0.0)]
        assert polished.shape[0] >= 1
        assert polished[:, 1].min() == pytest.approx(max(0.0, 0.5 - u0**2), abs=1e-6)
    assert set(np.round(N[:, 0], 12)) <= {0.25, 0.5, 0.75}


@pytest.mark.parametrize("problem", [CoilSpring, PressureVessel])
def test_default_reaches_the_best_known_mixed_design(problem: type) -> None:
    # Before the held polish the default ended 0.5-6.5 % above the coil spring's best known value at 50
    # simulations (N = 10 or 5 coils, or the diameter short of its constraint) and 0.9 % above the vessel's.
    p = problem()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = minimize(p, budget=50, method="auto", seed=1)
    assert r.fun <= p.f_min * (1.0 + 1e-6)
    assert np.all(p.on_grid(np.atleast_2d(r.x)))
