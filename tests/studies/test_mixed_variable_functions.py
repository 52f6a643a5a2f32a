"""The mixed-variable test problems reproduce their published best values at their best known designs."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.studies.catalogue import available_studies, load_study
from mechopt.studies.mixed_variable_functions import MIXED_SUITE, CoilSpring, GearTrain, PressureVessel, SpeedReducer

#: The literature's value, its printed design and the relative tolerance of the printed value's digits.
PUBLISHED = {
    "pressure_vessel": (6059.7143, [0.8125, 0.4375, 42.0984456, 176.6365958], 1e-8),
    "gear_train": (2.700857e-12, [16, 19, 43, 49], 1e-6),
    "coil_spring": (2.65856, [9, 1.223041, 0.283], 1e-5),
    "speed_reducer": (2994.4710661, [3.5, 0.7, 17, 7.3, 7.71532, 3.35021, 5.28665], 1e-9),
}


@pytest.mark.parametrize("name", sorted(MIXED_SUITE))
def test_best_known_design_reproduces_published_value(name: str) -> None:
    problem = MIXED_SUITE[name]()
    value, printed, rel = PUBLISHED[name]
    x = problem.x_min
    assert problem.feasible(x)[0], problem.margins(x)
    assert problem.on_grid(x)[0]
    assert np.array_equal(problem.snap(x), x)
    assert problem(x)[0] == pytest.approx(value, rel=rel)
    assert problem(x)[0] == pytest.approx(problem.f_min, rel=1e-9)
    # The declared design is the printed one solved to full precision: within the printed digits of it.
    np.testing.assert_allclose(x[0], printed, rtol=0, atol=6e-6)


def test_printed_designs_violate_their_active_limits_by_what_the_docstrings_say() -> None:
    pv, cs, sr = PressureVessel(), CoilSpring(), SpeedReducer()
    shell = pv.margins(np.array([PUBLISHED["pressure_vessel"][1]]))[0, 0]
    assert -1e-10 < shell < 0.0  # a relative 1e-10: 8e-11 in of thickness
    spring = cs.margins(np.array([PUBLISHED["coil_spring"][1]]))[0]
    assert -1e-7 < spring[6] < 0.0 and spring.min() == spring[6]
    reducer = sr.margins(np.array([PUBLISHED["speed_reducer"][1]]))[0]
    assert reducer[4] == pytest.approx(-4e-6, abs=5e-7) and reducer[5] == pytest.approx(-3e-6, abs=5e-7)
    assert sr(np.array([PUBLISHED["speed_reducer"][1]]))[0] == pytest.approx(2994.4670, abs=1e-4)


def test_gear_train_optimum_by_brute_force() -> None:
    # 49^4 designs: the ratio td*tb/(ta*tf) depends on two products only, so enumerate those.
    teeth = np.arange(12, 61)
    products = np.unique(np.outer(teeth, teeth))
    f = (1.0 / 6.931 - products[:, None] / products[None, :]) ** 2
    assert f.min() == pytest.approx(GearTrain.f_min, rel=1e-12)
    i, j = np.unravel_index(np.argmin(f), f.shape)
    assert (products[i], products[j]) == (16 * 19, 43 * 49)


def test_variables_mix_the_kinds_the_literature_uses() -> None:
    kinds = {name: [v.kind for v in cls.variables] for name, cls in MIXED_SUITE.items()}
    assert kinds["pressure_vessel"] == ["grid", "grid", "continuous", "continuous"]
    assert kinds["gear_train"] == ["integer"] * 4
    assert kinds["coil_spring"] == ["integer", "continuous", "catalogue"]
    assert kinds["speed_reducer"].count("integer") == 1
    assert PressureVessel.variables[0].count == 99 and CoilSpring.variables[2].count == 42


@pytest.mark.parametrize("name", sorted(MIXED_SUITE))
def test_each_problem_is_a_study_for_compare(name: str) -> None:
    assert name in available_studies()
    study = load_study(name)
    assert study.problem.name == name and study.kind == "test-function"
    study.problem.check()
