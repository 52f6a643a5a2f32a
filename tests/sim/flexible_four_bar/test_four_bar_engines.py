"""Exudyn's geometrically exact ANCF cables against the modal KED model (with its geometric terms) at the target and
at 20 random crank-rockers of the paper's 12-variable box whose links stay below a tenth of their Euler load."""

import numpy as np
import pytest

from mechopt.sim.flexible.response import normalised_error
from mechopt.sim.flexible_four_bar import FlexibleFourBar, simulate
from mechopt.sim.flexible_four_bar.kinematics import crank_rocker_margins
from mechopt.sim.flexible_four_bar.loads import euler_load_ratios
from mechopt.sim.flexible_four_bar.problem import ALL_VARIABLES, PAPER_BOUNDS

#: Largest axial compression over the Euler load of the designs compared: beyond it the deflections reach ~1 % of
#: the length and the linear model parts from the exact one (3-25 % of D's range at 0.2-0.4; README).
LOAD_RATIO = 0.1


def _designs(n: int, seed: int) -> list[FlexibleFourBar]:
    rng = np.random.default_rng(seed)
    lo, hi = (np.array([PAPER_BOUNDS[k][i] for k in ALL_VARIABLES]) for i in (0, 1))
    out = [FlexibleFourBar()]
    while len(out) < n + 1:
        x = rng.uniform(lo, hi)
        if np.all(crank_rocker_margins(x[None, :4]) > 0):
            v = dict(zip(ALL_VARIABLES, x, strict=True))
            p = FlexibleFourBar.from_mm(v["l1"], v["l2"], v["l3"], v["l4"], h3=v["h3"], a3=v["a3"], h4=v["h4"],
                                        a4=v["a4"], E3=v["E3"], rho3=v["rho3"], E4=v["E4"], rho4=v["rho4"])
            if max(euler_load_ratios(p)) <= LOAD_RATIO:
                out.append(p)
    return out


@pytest.fixture(scope="module")
def runs():
    return [(simulate(p, "exudyn"), simulate(p.with_(geometric_stiffness=True)), simulate(p))
            for p in _designs(20, seed=1)]


def test_paths_agree_to_a_thousandth_of_their_range(runs):
    for ex, mo, _ in runs:
        for k in ("crank", "coupler", "follower"):
            a, b = getattr(ex, k), getattr(mo, k)
            # measured worst 7.3e-4 of the range (follower y); the links' deflection is ~1e-2 of it
            assert np.max(np.abs(a - b) / np.ptp(b, axis=0)) < 1e-3


def test_deflections_agree_within_the_papers_error_measure(runs):
    worst, late = 0.0, 0.0
    for ex, mo, _ in runs:
        for k in ("D3", "D4"):
            a, b = getattr(ex, k), getattr(mo, k)
            worst = max(worst, normalised_error(a, b))  # Eq. 18 between the engines
            late = max(late, float(np.max(np.abs(a - b)[60:]) / np.ptp(b)))  # second crank turn
    # measured worst 6.0e-3 (Eq. 18) and 5.4e-3 (second turn); the first turn's start transient is where they part
    # most (up to 4 % of the range at one sample): the links' elastic inertia changes their axial forces there
    assert worst < 8e-3
    assert late < 8e-3


def test_geometric_terms_are_what_separates_the_papers_model(runs):
    ex, mo, paper = runs[0]  # the target: axial forces 2-5 % of the Euler load
    for k in ("D3", "D4"):
        exact, linear = getattr(ex, k), getattr(paper, k)
        assert normalised_error(linear, exact) > 5e-3  # measured 8.4e-3, 6.8e-3: 5-10x the engines' gap
        assert normalised_error(getattr(mo, k), exact) < 2e-3  # measured 1.2e-3, 8.0e-4
