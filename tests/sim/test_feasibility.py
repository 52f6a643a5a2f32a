"""Feasibility margins on designs straddling each constraint, and a design with two defects between the ends."""

import numpy as np
import pytest
from scipy.optimize import brentq

from mechopt.errors import InfeasibleDesignError
from mechopt.sim.four_bar.feasibility import check_feasibility, feasible_mask, require_movable
from mechopt.sim.four_bar.kinematics import crank_angle
from mechopt.sim.four_bar.load import RockerLoad
from mechopt.sim.four_bar.mechanism import FourBar
from mechopt.sim.four_bar.motion import MotionLaw


def _straddle(mechanism, column, base, index, lo, hi):
    """Designs 0.01 mm either side of where ``column`` crosses zero when length ``index`` runs from lo to hi."""

    def margin(x):
        d = np.array(base, float)
        d[index] = x
        return getattr(check_feasibility(d, mechanism), column)[0]

    root = brentq(margin, lo, hi, xtol=1e-9)
    inside, outside = np.array(base, float), np.array(base, float)
    step = 0.01 if margin(root + 0.01) > 0 else -0.01
    inside[index] = root + step
    outside[index] = root - step
    return inside, outside


@pytest.mark.parametrize(
    ("column", "base", "index", "lo", "hi"),
    [
        ("assembly_end_mm", (33.0, 70.0, 266.0), 1, 75.0, 90.0),  # |AB| too long: cannot reach ψ_end
        ("assembly_start_mm", (30.0, 120.0, 260.0), 1, 100.0, 120.0),  # |AB| too long at ψ_start
        ("toggle_deg", (33.246, 70.0, 266.088), 1, 75.0, 81.5),  # crank and coupler nearly aligned
    ],
)
def test_designs_straddling_a_constraint(mechanism, column, base, index, lo, hi):
    inside, outside = _straddle(mechanism, column, base, index, lo, hi)
    report = check_feasibility(np.vstack([inside, outside]), mechanism)
    margins = getattr(report, column)
    assert margins[0] > 0 > margins[1]
    assert not report.feasible[1]
    if column.startswith("assembly"):
        # The margin is a distance in mm: 0.01 mm either side of the boundary, to first order.
        np.testing.assert_allclose(np.abs(margins), 0.01, rtol=0.2)
    assert "infeasible" in report.message(1)


def _two_defect_geometry():
    """A geometry (found by a seeded search) whose crank reverses twice inside its wide stroke."""
    xc, yc, oa, ab, bc, p0, p1 = (-58.412148423603014, -76.58683626705267, 148.4811913735035, 175.11614336687592,
                                  64.7898180069846, -0.6807893598587111, 1.5407725903829683)
    mech = FourBar((xc, yc), 1e-3, 0.1, MotionLaw(p0, p1, 0.2), RockerLoad.constant(0.0), toggle_margin_deg=0.0)
    return mech, (oa, ab, bc)


def test_design_straddling_assembly_inside_the_stroke():
    # A longer rocker makes |OB| exceed |OA| + |AB| in the middle of the stroke while both ends still assemble:
    # the end-point test of Eq. 7 passes on both sides, the along-stroke margin changes sign.
    mech, (oa, ab, bc) = _two_defect_geometry()
    inside, outside = _straddle(mech, "assembly_stroke_mm", (oa, ab, bc), 2, 1.05 * bc, 1.1 * bc)
    report = check_feasibility(np.vstack([inside, outside]), mech)
    assert report.assembly_stroke_mm[0] > 0 > report.assembly_stroke_mm[1]
    np.testing.assert_allclose(np.abs(report.assembly_stroke_mm), 0.01, rtol=0.3)
    assert np.all(report.assembly_start_mm > 1) and np.all(report.assembly_end_mm > 1)  # Eq. 7 sees nothing
    assert not report.movable[1]
    assert "not assemblable inside the stroke" in report.message(1)


def test_assembly_margin_by_hand(mechanism):
    # At ψ_end, |OB| is known in closed form; the margin is |OA| + |AB| − |OB| for a long-reaching design.
    oa, ab, bc = 40.0, 80.0, 270.0
    xc, yc = mechanism.pivot_c
    ob = np.hypot(xc + bc * np.cos(mechanism.psi_end), yc + bc * np.sin(mechanism.psi_end))
    report = check_feasibility((oa, ab, bc), mechanism)
    assert report.assembly_end_mm[0] == pytest.approx(min(oa + ab - ob, ob - abs(oa - ab)), abs=1e-9)


def test_two_defects_between_the_ends_are_caught():
    # θ' has the same sign at both ends, so the end-point test of Eq. 8 passes, yet the crank is not monotonic.
    mech, (oa, ab, bc) = _two_defect_geometry()
    psi = np.linspace(mech.psi_start, mech.psi_end, 4001)
    _, d1, _ = crank_angle((oa, ab, bc), mech.pivot_c, psi)
    signs = np.sign(d1)
    assert np.all(np.isfinite(d1))
    assert signs[0] == signs[-1]  # Eq. 8 sees nothing
    assert np.count_nonzero(np.diff(signs)) == 2  # two reversals in between
    report = check_feasibility((oa, ab, bc), mech)
    assert report.monotonic_deg[0] < 0
    assert not report.movable[0]
    with pytest.raises(InfeasibleDesignError, match="not monotonic"):
        require_movable(np.array([oa, ab, bc]), mech)


def test_vectorised_equals_one_by_one(mechanism, ventilator):
    rng = np.random.default_rng(7)
    designs = rng.uniform(ventilator.problem.bounds[:, 0], ventilator.problem.bounds[:, 1], size=(40, 3))
    batch = check_feasibility(designs, mechanism)
    for i in range(0, 40, 7):
        single = check_feasibility(designs[i], mechanism)
        assert single.margins(0) == pytest.approx(batch.margins(i), nan_ok=True)
    mask = feasible_mask(np.vstack([designs, [[-1, 60, 260]]]), mechanism)
    np.testing.assert_array_equal(mask[:-1], batch.feasible)
    assert not mask[-1]
