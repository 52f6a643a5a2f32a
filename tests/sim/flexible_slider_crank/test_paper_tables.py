"""Paper 004, Table 5: the velocity error f(V) (Eq. 21) of the seven algorithms' designs against the target."""

import numpy as np
import pytest

from mechopt.sim.flexible_slider_crank import normalised_error
from mechopt.sim.flexible_slider_crank.kinematics import rigid_motion

OMEGA = 26.19
T = np.linspace(0.0, 0.48, 121)  # 121 samples over two crank turns (0.48 s), as printed


def f_v(l2_mm, l3_mm):
    ref = rigid_motion(50.0 * 1e-3, 350.0 * 1e-3, OMEGA, T).v
    return normalised_error(rigid_motion(l2_mm * 1e-3, l3_mm * 1e-3, OMEGA, T).v, ref)


@pytest.mark.parametrize(("l2", "l3", "printed"), [
    (49.9860, 349.8059, 9.7182e-5),  # BBA
    (50.0010, 350.0544, 7.6991e-6),  # HO
    (50.0115, 349.8703, 8.3273e-5),  # IW
])
def test_table5_errors_within_2_percent(l2, l3, printed):
    assert f_v(l2, l3) == pytest.approx(printed, rel=0.02)


@pytest.mark.parametrize("name", ["CA", "SC", "SF"])
def test_table5_exact_lengths_give_zero(name):
    # printed 0 with l2 = 50, l3 = 350 and another material and section: V is rigid kinematics
    assert f_v(50.0, 350.0) == 0.0
