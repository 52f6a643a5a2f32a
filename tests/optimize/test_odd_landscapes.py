"""The default method on landscapes with a closed-form answer that a smooth model does not expect: a plane, whose
minimum is the vertex its gradient points away from, and plateaus, where the model sees no gradient at all but the
zero step. Both at 10d simulations, in 2, 5 and 12 variables (the global plan and the trust region)."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt import minimize
from mechopt.optimize.problem import DesignProblem, Variable


def _problem(dim: int, f) -> DesignProblem:
    class Landscape(DesignProblem):
        name = f"landscape{dim}"
        variables = tuple(Variable(f"x{i}", -1.0, 2.0) for i in range(dim))
        outputs = ("f",)
        objective = "f"

        def evaluate(self, x):
            return {"f": f(np.asarray(x, dtype=float))}

    return Landscape()


def _gradient(dim: int) -> np.ndarray:
    # Alternating signs and growing magnitudes: the vertex is no corner a symmetric design would favour.
    return np.array([(-1.0) ** i * (1.0 + i) for i in range(dim)])


@pytest.mark.parametrize("dim", [2, 5, 12])
def test_a_plane_ends_exactly_on_the_vertex_its_gradient_points_away_from(dim):
    g = _gradient(dim)
    vertex = np.where(g > 0, -1.0, 2.0)
    res = minimize(_problem(dim, lambda x: float(g @ x)), budget=10 * dim, seed=0)
    assert res.nfev == 10 * dim
    np.testing.assert_array_equal(res.x, vertex)
    assert res.fun == pytest.approx(float(g @ vertex), abs=1e-12)


@pytest.mark.parametrize("dim", [2, 5])
def test_plateaus_lead_down_to_the_zero_step(dim):
    centre = np.linspace(0.1, 0.9, dim)

    def steps(x):
        # Integer steps of a bowl: zero within 0.45 of the centre in every variable, flat everywhere.
        return float(np.sum(np.floor(5.0 * (x - centre) ** 2)))

    res = minimize(_problem(dim, steps), budget=10 * dim, seed=0)
    assert res.fun == 0.0
    assert np.all(5.0 * (res.x - centre) ** 2 < 1.0)


def test_a_constant_objective_spends_the_budget_and_returns_a_design():
    res = minimize(_problem(3, lambda x: 1.5), budget=12, seed=0)
    assert res.success and res.fun == 1.5 and res.nfev == 12 and res.nfailed == 0
    assert np.all((res.x >= -1.0) & (res.x <= 2.0))
