"""Paper 003's rowing study: the reconstructed desired effort against the paper's log, the optimum, bad studies."""

import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize

from mechopt.errors import StudyError
from mechopt.sim.slider_crank.rowing_reconstruction import (
    PAPER_LOG,
    desired_effort,
    fminunc_log,
    paper_angles,
)
from mechopt.studies.kinds.rowing import problem_from_study
from mechopt.studies.study_file import PACKAGED_STUDIES, StudyFile

STUDY = PACKAGED_STUDIES / "rowing" / "study.toml"


def _study(folder=None, **changes):
    config = tomllib.loads(STUDY.read_text())
    for section, values in changes.items():
        config.setdefault(section, {}).update(values)
    return StudyFile(STUDY if folder is None else Path(folder) / "study.toml", config, "rowing")


@pytest.fixture(scope="module")
def problem():
    return problem_from_study(_study(), {})


def test_data_file_is_the_reconstruction(problem):
    theta, fd_kn = desired_effort()
    np.testing.assert_allclose(problem.theta, theta, atol=1e-12)
    np.testing.assert_array_equal(problem.desired, fd_kn * 1000.0)
    assert problem.theta.size == 63 and problem.theta[-1] == pytest.approx(6.2)  # the code's t = 0:0.1:2π
    assert problem.desired.max() == pytest.approx(4100.0) and 2500.0 < problem.desired.min() < 2501.0  # π off the grid


def test_replayed_solver_reproduces_every_line_of_the_paper_log(problem):
    log = fminunc_log(problem.theta, problem.desired)
    assert [row[0] for row in log] == [row[0] for row in PAPER_LOG]  # 21 evaluations in 6 iterations
    for (_, f, step, opt), (_, f_p, step_p, opt_p) in zip(log, PAPER_LOG, strict=True):
        assert f == pytest.approx(f_p, rel=5e-3)  # the last line: 8.2187e-4 against 8.25424e-4 N²
        assert opt == pytest.approx(opt_p, rel=0.05)  # printed to 3 digits at best
        if step_p is not None:
            assert step == pytest.approx(step_p, rel=1e-5)
    assert log[0][1] == pytest.approx(4.33715e6, rel=1e-5) and log[1][1] == pytest.approx(3.38903e6, rel=1e-5)


def test_printed_optimum_does_not_give_the_printed_error(problem):
    assert problem.evaluate(np.array([3.3, 13.5]))["mse_N2"] == pytest.approx(59.05, abs=0.01)


def test_true_optimum_by_grid_and_polish(problem):
    g = np.meshgrid(np.linspace(1, 10, 61), np.linspace(11, 20, 61), indexing="ij")
    X = np.column_stack([v.ravel() for v in g])
    f = np.array([problem.evaluate(x)["mse_N2"] for x in X])
    res = minimize(lambda x: problem.evaluate(x)["mse_N2"], X[np.argmin(f)], method="Nelder-Mead",
                   options={"xatol": 1e-10, "fatol": 1e-14, "maxiter": 2000})
    np.testing.assert_allclose(res.x, [3.278676, 13.524580], atol=2e-6)
    assert res.fun == pytest.approx(8.2187e-4, rel=1e-4)
    # The rounding floor of F_d in 0.1 N steps: ≈ 0.1²/12 N².
    assert res.fun == pytest.approx(0.1**2 / 12, rel=0.05)


def test_bad_studies_are_one_line_errors(tmp_path):
    with pytest.raises(StudyError, match="no feasible design"):
        problem_from_study(_study(variables={"l2": [15.0, 20.0], "l3": [11.0, 14.0]}), {})
    (tmp_path / "neg.csv").write_text("theta_rad,fd_kN\n" + "".join(f"{t:.1f},-1.0\n" for t in paper_angles()))
    with pytest.raises(StudyError, match="unreachable"):
        problem_from_study(_study(tmp_path, effort={"desired": "neg.csv"}), {})
    with pytest.raises(StudyError, match="not found"):
        problem_from_study(_study(tmp_path, effort={"desired": "missing.csv"}), {})
    (tmp_path / "bad.csv").write_text("theta,F\n0,1\n")
    with pytest.raises(StudyError, match="header"):
        problem_from_study(_study(tmp_path, effort={"desired": "bad.csv"}), {})


def test_figures(problem, tmp_path):
    figs = problem.figures({"paper_optimum": np.array([3.3, 13.5])}, tmp_path)
    assert len(figs) == 3
    for path in figs.values():
        assert path.is_file() and path.stat().st_size > 1000


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_default_method_takes_the_least_squares_plan_to_the_exact_optimum(problem, seed):
    import mechopt

    res = mechopt.minimize(problem, budget=30, method="auto", seed=seed)
    assert res.plan == "least-squares" and res.nfev <= 30
    # measured 3.7e-7 mm from the brute-force optimum (the compare section's value is rounded to 1e-6 mm)
    np.testing.assert_allclose(res.x, [3.278676, 13.524580], atol=2e-6)
    assert res.fun == pytest.approx(8.2187e-4, rel=1e-4)


def test_residuals_are_the_mean_square_error_split(problem):
    out = problem.evaluate(np.array([3.0, 14.0]))
    r = problem.residual_vector(out)
    assert r.size == problem.theta.size
    assert float(r @ r) == pytest.approx(out["mse_N2"], rel=1e-12)
