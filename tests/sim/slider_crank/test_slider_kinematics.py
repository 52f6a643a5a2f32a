"""Slider-crank kinematics against closed forms, geometry and finite differences; limits, stroke, time ratio."""

import numpy as np
import pytest

from mechopt.errors import InfeasibleDesignError, InputError
from mechopt.sim.slider_crank.feasibility import margins, require_assemblable
from mechopt.sim.slider_crank.kinematics import (
    joint_positions,
    rod_angle,
    slider_position,
    transmission_angle,
    transmission_extremes,
)
from mechopt.sim.slider_crank.limits import dead_centre_angle, limit_positions, stroke, time_ratio


def _designs(seed, n=8):
    rng = np.random.default_rng(seed)
    r = rng.uniform(20, 100, n)
    h = rng.uniform(-1.0, 1.0, n) * r
    l = (r + np.abs(h)) * rng.uniform(1.05, 3.0, n)
    return np.column_stack([r, l, h])


@pytest.mark.parametrize("branch", [1, -1])
def test_loop_closes_and_derivatives_match_finite_differences(branch):
    theta = np.linspace(-np.pi, np.pi, 181)
    for d in _designs(1):
        pos = joint_positions(d, theta, branch)
        # |AB| = l and B on the line y = h, to rounding.
        np.testing.assert_allclose(np.linalg.norm(pos["B"] - pos["A"], axis=-1), d[1], rtol=1e-12)
        np.testing.assert_allclose(pos["B"][:, 1], d[2], atol=1e-12)
        assert np.all(branch * (pos["B"][:, 0] - pos["A"][:, 0]) > 0)
        x, dx, ddx = slider_position(d, theta, branch)
        phi, dphi, ddphi = rod_angle(d, theta, branch)
        e = 1e-5
        xp, xm = slider_position(d, theta + e, branch)[0], slider_position(d, theta - e, branch)[0]
        np.testing.assert_allclose(dx, (xp - xm) / (2 * e), atol=1e-6 * d[1])
        np.testing.assert_allclose(ddx, (xp - 2 * x + xm) / e**2, atol=2e-3 * d[1])
        pp, pm = rod_angle(d, theta + e, branch)[0], rod_angle(d, theta - e, branch)[0]
        dphi_fd = (np.unwrap(np.stack([pm, pp]), axis=0)[1] - np.unwrap(np.stack([pm, pp]), axis=0)[0]) / (2 * e)
        np.testing.assert_allclose(dphi, dphi_fd, atol=1e-6)
        dp_p, dp_m = rod_angle(d, theta + e, branch)[1], rod_angle(d, theta - e, branch)[1]
        np.testing.assert_allclose(ddphi, (dp_p - dp_m) / (2 * e), atol=1e-5)


def test_in_line_position_is_the_paper_003_formula():
    theta = 0.1 * np.arange(63)
    x, _, _ = slider_position((3.3, 13.5, 0.0), theta)
    np.testing.assert_allclose(x, 3.3 * np.cos(theta) + np.sqrt(13.5**2 - (3.3 * np.sin(theta)) ** 2), rtol=1e-14)


def test_loop_open_is_nan():
    x, dx, _ = slider_position((50.0, 60.0, 30.0), np.array([-np.pi / 2, 0.0]))
    assert np.isnan(x[0]) and np.isfinite(x[1])  # |h − r sin θ| = 80 > 60 at θ = −90°


def test_limits_stroke_and_time_ratio_against_a_dense_crank_sweep():
    theta = np.linspace(0.0, 2 * np.pi, 400001)
    for r, l, h in _designs(2):
        x, dx, _ = slider_position((r, l, h), theta)
        lim = limit_positions(r, l, h)
        assert lim["x_extended"] == pytest.approx(x.max(), rel=1e-9)
        assert lim["x_folded"] == pytest.approx(x.min(), rel=1e-9)
        # The slider is at rest at the dead centres.
        for key in ("theta_extended", "theta_folded"):
            assert abs(slider_position((r, l, h), lim[key])[1]) < 1e-9 * l
        assert stroke(r, l, h) == pytest.approx(x.max() - x.min(), rel=1e-9)
        # Time ratio at constant crank speed: share of the revolution with the slider going each way.
        forward = np.mean(dx[:-1] > 0)
        slow, fast = max(forward, 1 - forward), min(forward, 1 - forward)
        assert time_ratio(r, l, h) == pytest.approx(slow / fast, rel=2e-4)
        assert np.degrees(abs(dead_centre_angle(r, l, h))) == pytest.approx(180 * (slow - fast), abs=2e-3)


def test_mirror_branch_has_mirrored_limits():
    lim_r = limit_positions(40.0, 120.0, 25.0, branch=1)
    lim_l = limit_positions(40.0, 120.0, 25.0, branch=-1)
    assert lim_l["x_extended"] == pytest.approx(-lim_r["x_extended"])
    x, _, _ = slider_position((40.0, 120.0, 25.0), lim_l["theta_extended"], branch=-1)
    assert x == pytest.approx(lim_l["x_extended"], rel=1e-12)


def test_transmission_extremes_and_margins():
    theta = np.linspace(0.0, 2 * np.pi, 200001)
    for r, l, h in _designs(3):
        ta = transmission_angle((r, l, h), theta)
        lo, hi = transmission_extremes(r, l, h)
        assert lo == pytest.approx(ta.min(), abs=1e-6) and hi == pytest.approx(ta.max(), abs=1e-6)
        m = margins((r, l, h), (40.0, 140.0))[0]
        assert m[0] == pytest.approx(l - r - abs(h))
        assert m[1] == pytest.approx(lo - 40.0) and m[2] == pytest.approx(140.0 - hi)
    assert np.all(margins((50.0, 60.0, 30.0))[0] < 0)  # no full rotation: every margin violated


def test_bad_input_is_one_line():
    with pytest.raises(InputError, match="crank r"):
        slider_position((0.0, 10.0, 0.0), 0.0)
    with pytest.raises(InputError, match="branch"):
        slider_position((1.0, 10.0, 0.0), 0.0, branch=2)
    with pytest.raises(InfeasibleDesignError, match="cannot turn fully"):
        require_assemblable(np.array([50.0, 60.0, 10.0]))
