"""Leave-one-line-out error and blend spread (surrogate.line_error)."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.surrogate import LinePlan, SparseExponentialModel, SurrogateError
from mechopt.surrogate.line_error import blend_spread, leave_one_line_out

# Ten lines along z through a 2-D set of nodes in the (x, y) plane; 15 samples each, 0.1 apart.
NODES = np.array([[0, 0], [1, 0], [2, 0], [0, 1], [1, 1], [2, 1], [0, 2], [1, 2], [2, 2], [0.5, 1.5]], dtype=float)
KS = np.arange(15)


def _plan() -> LinePlan:
    offsets = np.column_stack([NODES, np.zeros(len(NODES))])
    return LinePlan(np.array([0.0, 0.0, 0.1]), np.zeros(3), offsets,
                    k_ranges=np.tile([KS[0], KS[-1]], (len(NODES), 1)))


def _fit(field):
    plan = _plan()
    values = [field(plan.points(i, KS)) for i in range(plan.n_lines)]
    model = SparseExponentialModel(order=1 if field is _smooth else None, max_order=5).fit(
        plan, [(KS, v) for v in values])
    return model, values


def _smooth(X: np.ndarray) -> np.ndarray:
    # Linear across the lines times one exponential along them: every leave-one-out blend of >= 3 nodes (complete
    # degree >= 1) reproduces it, and the 1-D fits are exact.
    return (2.0 + 0.3 * X[:, 0] - 0.2 * X[:, 1]) * np.exp(-0.8 * X[:, 2])


def _bumpy(X: np.ndarray) -> np.ndarray:
    # A narrow well between the lines (centre (1.5, 0.5), width 0.3 < the node spacing 1): no blend can see it where
    # it is, and the lines that graze it disagree with their neighbours.
    return _smooth(X) - 1.5 * np.exp(-((X[:, 0] - 1.2) ** 2 + (X[:, 1] - 0.6) ** 2) / 0.09)


def test_exactly_representable_field_has_no_line_out_error():
    model, values = _fit(_smooth)
    err = leave_one_line_out(model, values)
    assert err.rms.shape == (10,)
    assert err.max < 1e-8
    X = np.array([[0.3, 0.7, 0.5], [1.6, 1.9, 1.0], [1.0, 1.0, 0.2]])
    assert np.all(blend_spread(model, X) < 1e-8)


def test_feature_between_lines_shows_in_both_measures():
    model, values = _fit(_bumpy)
    err = leave_one_line_out(model, values)
    assert err.max > 0.05
    # The interior line nearest the well, (1, 1), is predicted by its neighbours far worse than on the smooth field.
    assert err.relative[4] > 0.01
    # At the well the leave-one-out blends disagree by more than 1 % of the range (0 for the smooth field).
    assert blend_spread(model, np.array([[1.2, 0.6, 0.7]]))[0] > 0.01 * err.value_range


def test_checks_its_input():
    model, values = _fit(_smooth)
    with pytest.raises(SurrogateError):
        leave_one_line_out(model, values[:-1])
    with pytest.raises(SurrogateError):
        leave_one_line_out(model, [v[:-1] for v in values])
