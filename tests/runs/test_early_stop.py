"""A run whose simulator fails from its first design stops after a few simulations, with the first reason (issue 52).

Real simulators: a Python callable and an external command (a subprocess per design), each counting its calls in a
file; real worker processes for W = 2.
"""

from __future__ import annotations

import zlib
from pathlib import Path

import numpy as np
import pytest

import mechopt
from mechopt.cli.main import main
from mechopt.errors import BrokenSimulatorError, InputError
from mechopt.studies.catalogue import load_study

# Each failure kind of a broken simulator, and the reason the run's line must name.
FAILURES = {
    "raises": ("raise RuntimeError('licence server not found')", "RuntimeError: licence server not found"),
    "nan": ("out = {'f': float('nan')}", "'f' is not finite: nan"),
    "missing": ("out = {'g': 1.0}", "'f'"),
}

CALLABLE = '''
def simulate(d):
    with open({counter!r}, "a") as fh:
        fh.write("x\\n")
    {body}
    return out
'''

COMMAND = '''
import json, sys
d = json.load(sys.stdin)
with open({counter!r}, "a") as fh:
    fh.write("x\\n")
{body}
print(json.dumps(out))
'''


def write_study(folder: Path, kind: str, failure: str) -> Path:
    """A study of kind "external" over a, b in [0, 4] whose simulator always fails the given way."""
    # The counter's path is written into the simulator: worker processes fork from a server started by an earlier
    # test, with that test's environment.
    counter = str(folder / "calls.txt")
    body = FAILURES[failure][0]
    if kind == "callable":
        # A module name of its own: an in-process run imports it into this process, once per name.
        module = f"broken_sim_{zlib.crc32(str(folder).encode())}"
        (folder / f"{module}.py").write_text(CALLABLE.replace("{body}", body).replace("{counter!r}", repr(counter)))
        simulator = f'callable = "{module}:simulate"'
    else:
        (folder / "broken_sim.py").write_text(COMMAND.replace("{body}", body).replace("{counter!r}", repr(counter)))
        simulator = 'command = ["{python}", "broken_sim.py"]\ntimeout_s = 30'
    toml = folder / "study.toml"
    toml.write_text(f'name = "broken-{kind}-{failure}"\nkind = "external"\n[variables]\na = [0.0, 4.0]\n'
                    f'b = [0.0, 4.0]\n[simulator]\n{simulator}\noutputs = ["f"]\n')
    return toml


def calls(folder: Path) -> int:
    path = folder / "calls.txt"
    return len(path.read_text().splitlines()) if path.exists() else 0


@pytest.mark.parametrize("kind", ["callable", "command"])
@pytest.mark.parametrize("failure", sorted(FAILURES))
def test_a_broken_simulator_stops_after_five_with_the_first_reason(tmp_path, kind, failure):
    problem = load_study(write_study(tmp_path, kind, failure)).problem
    with pytest.raises(BrokenSimulatorError) as info:
        mechopt.minimize(problem, budget=60, method="auto", seed=0, store=tmp_path / "s.sqlite")
    assert calls(tmp_path) == 5
    message = str(info.value)
    assert "\n" not in message and "the first 5 simulations all failed" in message
    assert FAILURES[failure][1] in message


@pytest.mark.parametrize("method", ["auto", "sparse", "sparse-global", "differential_evolution", "nelder_mead",
                                    "optuna_tpe"])
def test_every_method_through_the_sampler_stops_early(tmp_path, method):
    problem = load_study(write_study(tmp_path, "callable", "raises")).problem
    with pytest.raises(BrokenSimulatorError, match="licence server not found"):
        mechopt.minimize(problem, budget=60, method=method, seed=0)
    assert calls(tmp_path) == 5


@pytest.mark.parametrize(("kind", "method"), [("callable", "auto"), ("command", "sparse"),
                                              ("callable", "differential_evolution")])
def test_with_two_workers_at_most_five_plus_two(tmp_path, kind, method):
    problem = load_study(write_study(tmp_path, kind, "nan")).problem
    with pytest.raises(BrokenSimulatorError):
        mechopt.minimize(problem, budget=60, method=method, seed=0, workers=2)
    assert 5 <= calls(tmp_path) <= 5 + 2


def test_the_option_sets_k_and_zero_spends_the_budget(tmp_path):
    problem = load_study(write_study(tmp_path, "callable", "missing")).problem
    with pytest.raises(BrokenSimulatorError, match="the first 3 simulations"):
        mechopt.minimize(problem, budget=20, seed=0, stop_after_failures=3)
    assert calls(tmp_path) == 3
    result = mechopt.minimize(problem, budget=20, seed=0, stop_after_failures=0)
    assert not result.success and result.nfailed == 20 and calls(tmp_path) == 3 + 20
    with pytest.raises(InputError, match="stop_after_failures = -1"):
        mechopt.minimize(problem, budget=20, seed=0, stop_after_failures=-1)


def test_failures_after_a_success_stay_a_hidden_constraint(tmp_path):
    # Fails everywhere but where a > 3.5: if the first design succeeds nothing stops the run, though most fail.
    class MostlyBroken(mechopt.DesignProblem):
        name = "mostly-broken"
        variables = (mechopt.Variable("a", 0.0, 4.0, "mm"), mechopt.Variable("b", 0.0, 4.0, "mm"))
        outputs = ("f",)
        objective = "f"

        def evaluate(self, x):
            if x[0] < 3.5:
                raise RuntimeError("solver diverged")
            return {"f": float((x[0] - 3.8) ** 2 + x[1] ** 2)}

    result = mechopt.minimize(MostlyBroken(), budget=30, seed=0, x0=[3.9, 1.0])
    assert result.success and result.nfev == 30 and result.nfailed >= 5
    assert np.isfinite(result.fun)


def test_mechopt_study_ends_in_one_line(tmp_path, capsys):
    toml = write_study(tmp_path, "command", "raises")
    code = main(["study", str(toml), "--out", str(tmp_path / "out"), "--no-progress", "--workers", "1",
                 "--budget", "60", "--method", "auto"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0 and calls(tmp_path) == 5
    assert len(err) == 1 and "the first 5 simulations all failed" in err[0] and "--retry-failed" in err[0]
    code = main(["study", str(toml), "--out", str(tmp_path / "out"), "--no-progress", "--workers", "1",
                 "--budget", "60", "--method", "auto", "--stop-after-failures", "2", "--retry-failed"])
    assert code != 0 and calls(tmp_path) == 5 + 2
