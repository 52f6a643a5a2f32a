"""The multi-objective suite against pymoo's implementations, and its front bounds against pymoo's fronts."""

from __future__ import annotations

import numpy as np
import pytest

from mechopt.studies.multi_objective_functions import MULTI_OBJECTIVE_SUITE

pymoo_problems = pytest.importorskip("pymoo.problems")

#: Our name -> pymoo's name and arguments.
PYMOO = {"zdt1": ("zdt1", {"n_var": 5}), "zdt2": ("zdt2", {"n_var": 5}), "zdt3": ("zdt3", {"n_var": 5}),
         "dtlz2": ("dtlz2", {"n_var": 5, "n_obj": 2}), "dtlz2-3": ("dtlz2", {"n_var": 6, "n_obj": 3}),
         "bnh": ("bnh", {}), "srn": ("srn", {}), "tnk": ("tnk", {}), "osy": ("osy", {})}


@pytest.mark.parametrize("name", sorted(MULTI_OBJECTIVE_SUITE))
def test_values_match_pymoo(name):
    ours = MULTI_OBJECTIVE_SUITE[name]()
    theirs = pymoo_problems.get_problem(PYMOO[name][0], **PYMOO[name][1])
    assert np.allclose(ours.bounds[:, 0], theirs.xl, atol=1e-12) and np.allclose(ours.bounds[:, 1], theirs.xu)
    rng = np.random.default_rng(0)
    X = ours.bounds[:, 0] + rng.random((50, ours.dim)) * (ours.bounds[:, 1] - ours.bounds[:, 0])
    F, G = ours.function(X)
    out = theirs.evaluate(X, return_values_of=["F", "G"])
    assert np.allclose(F, out[0], rtol=1e-12, atol=1e-12)
    if ours.n_constraints:
        assert np.allclose(G, out[1], rtol=1e-12, atol=1e-12)
    # One design through evaluate(): the outputs by name, the constraints as limits <= 0.
    outputs = ours.evaluate(X[0])
    assert [outputs[n] for n in ours.objective] == pytest.approx(F[0])
    assert all(ours.limits[f"c{j + 1}"] == (None, 0.0) for j in range(ours.n_constraints))
    ours.check()


@pytest.mark.parametrize("name", ["zdt1", "zdt2", "zdt3", "dtlz2", "dtlz2-3", "bnh", "srn"])
def test_ideal_and_nadir_are_those_of_pymoos_front(name):
    ours = MULTI_OBJECTIVE_SUITE[name]
    front = pymoo_problems.get_problem(PYMOO[name][0], **PYMOO[name][1]).pareto_front()
    assert np.allclose(front.min(axis=0), ours.ideal, atol=1e-6)
    assert np.allclose(front.max(axis=0), ours.nadir, atol=1e-6)


def test_listed_by_mechopt_studies():
    from mechopt.cli.catalogue_commands import study_lines

    lines = study_lines()
    for name in MULTI_OBJECTIVE_SUITE:
        assert any(line.split()[0] == name and "objectives" in line for line in lines)
