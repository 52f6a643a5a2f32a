"""Gauss-Newton on the path-synthesis residuals: from the paper's Table 2 design it walks along the active 3:1 ratio
constraint to a constrained minimum below the paper's E = 0.0073 (the paper's design sits where the shortest bar
changes: the constraint's kink, which the smooth pieces of the study's margins let a linearising method pass)."""

import numpy as np
import pytest

import mechopt
from mechopt.errors import InfeasibleDesignError
from mechopt.optimize.least_squares import least_squares_polish


@pytest.fixture(scope="module")
def study():
    return mechopt.load_study("path-synthesis-1")


def _residuals(problem):
    def evaluate(X):
        values, R = [], []
        for x in X:
            try:
                out = problem.evaluate(x)
            except InfeasibleDesignError:  # recorded as a failure, as the sample store does
                values.append(np.nan)
                R.append(None)
                continue
            values.append(out["E"])
            R.append(problem.residual_vector(out))
        return np.array(values), R

    return evaluate


def test_polish_from_the_papers_design_reaches_the_constrained_minimum(study):
    p = study.problem
    x, run = least_squares_polish(_residuals(p), p.bounds, study.design("paper_table2"), budget=200, fd_step=1e-6,
                                  feasible=p.feasible, margins=p.constraint_margins)
    assert p.feasible(x)[0]
    # measured E = 0.0061513 in 68 simulations, converged on both constraints (0.0072784 with the ratio as one
    # kinked margin; 0.0063693 while designs on the constraint were rounded to the store's key); paper: 0.0073
    assert run.value == pytest.approx(0.0061513, rel=1e-3)
    assert run.value >= study.problem.evaluate(study.design("best_found"))["E"] - 1e-9
    assert abs(p.named_margins(x)["bar_ratio"]) < 1e-9  # the 3:1 ratio of the longest to the shortest bar is active
    assert abs(p.named_margins(x)["grashof"]) < 1e-9  # and so is the Grashof margin
