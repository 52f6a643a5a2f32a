"""Each mechopt method refuses a budget below its own minimum in one line, before any simulation, and a budget at
the minimum is spent, not overrun: the budget is the cost (the sparse method once spent 7 simulations of a budget
of 3, the least its line plan takes)."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt import minimize
from mechopt.errors import InputError
from mechopt.optimize.arguments import method_min_budget
from mechopt.studies.benchmark_functions import Branin, Hartmann3, Hartmann4


@pytest.mark.parametrize(("problem", "method", "need"), [
    (Branin(), "sparse", 7),  # 3 lines of 2 and the confirmation
    (Hartmann3(), "sparse", 7),
    (Hartmann4(), "sparse", 11),  # a 3-D blend needs 5 lines
    (Hartmann3(), "sparse-global", 30),
    (Hartmann4(), "auto", 10),
])
def test_below_the_minimum_is_refused_in_one_line(problem, method, need):
    assert method_min_budget(method, problem.dim)[0] == need
    with pytest.raises(InputError) as info:
        minimize(problem, need - 1, method=method)
    text = str(info.value)
    assert f"= {need} simulations" in text and f"budget = {need - 1}" in text and "\n" not in text


@pytest.mark.parametrize("problem", [Branin(), Hartmann3(), Hartmann4()])
def test_the_sparse_minimum_is_spent_not_overrun(problem):
    need = method_min_budget("sparse", problem.dim)[0]
    r = minimize(problem, need, method="sparse", seed=0, options={"search_points": 20_000})
    assert r.nfev <= need
    assert np.isfinite(r.fun)


def test_fewer_lines_lower_the_minimum():
    # The caller's own line count sets the minimum: 2 lines of 2 and the confirmation.
    with pytest.raises(InputError, match="= 5 simulations"):
        minimize(Hartmann3(), 4, method="sparse", options={"n_lines": 2})
    assert method_min_budget("sparse", 3, n_lines=2)[0] == 5
