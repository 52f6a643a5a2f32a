"""The Python-callable simulator in worker processes, ``mechopt study`` on a study of kind "external", and the
packaged ventilator-command example against the in-process engine."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

from mechopt.cli.main import main
from mechopt.runs.executors import make_executor
from mechopt.runs.sampling import sample_designs
from mechopt.runs.store import SampleStore
from mechopt.studies.catalogue import load_study

MODULE = '''
import math
from mechopt.errors import InfeasibleDesignError

def simulate(d):
    a, b = d["a"], d["b"]
    if a == 3.0:
        raise RuntimeError("mesh generation failed\\nat element 7")
    if a == 2.5:
        raise InfeasibleDesignError("collides with the housing")
    if a == 2.0:
        return {"f": 1.0}
    if a == 1.5:
        return {"f": math.nan, "g": 0.0}
    return {"f": (a - 1.0) ** 2 + b, "g": a * b, "note": "ok"}
'''


def write_callable_study(folder):
    (folder / "toy_callable_sim.py").write_text(MODULE)
    toml = folder / "study.toml"
    toml.write_text('name = "toy-callable"\nkind = "external"\n[variables]\na = [0.0, 4.0]\nb = [0.0, 4.0]\n'
                    '[simulator]\ncallable = "toy_callable_sim:simulate"\noutputs = ["f", "g"]\n')
    return toml


def test_callable_failures_are_recorded_in_worker_processes(tmp_path):
    problem = load_study(write_callable_study(tmp_path)).problem
    assert problem.objective == "f" and problem.fit == "value"
    designs = [(0.5, 1.0), (3.0, 1.0), (2.5, 1.0), (2.0, 1.0), (1.5, 1.0)]
    with SampleStore(tmp_path / "s.sqlite") as store, make_executor(workers=2) as ex:
        res = sample_designs(designs, problem, store, executor=ex, progress=False)
    ok, exc, infeasible, missing, nan = res.records
    assert ok.status == "ok" and ok.outputs == {"f": 1.25, "g": 0.5, "note": "ok"}
    assert exc.status == "failed" and exc.error == "RuntimeError: mesh generation failed at element 7"
    assert infeasible.status == "infeasible" and infeasible.error == "collides with the housing"
    assert missing.status == "failed" and "output 'g' missing" in missing.error
    assert nan.status == "failed" and "'f' is not finite: nan" in nan.error
    # Imported in the workers only: the study's folder is not put on this process's sys.path.
    assert "toy_callable_sim" not in sys.modules and str(tmp_path) not in sys.path


def test_editing_the_callable_module_changes_the_fingerprint(tmp_path):
    toml = write_callable_study(tmp_path)
    fp = load_study(toml).problem.fingerprint()
    (tmp_path / "toy_callable_sim.py").write_text(MODULE.replace("(a - 1.0) ** 2", "(a - 1.1) ** 2"))
    assert load_study(toml).problem.fingerprint() != fp


def test_mechopt_study_on_an_external_command_finds_the_known_optimum(tmp_path, capsys):
    # f = 1 + (a - 1.3)² + 2 (b - 0.7)², exact minimum 1 at (1.3, 0.7) mm, behind a separate program.
    (tmp_path / "bowl.py").write_text(
        "import json, sys\nd = json.load(sys.stdin)\n"
        "print(json.dumps({'f': 1 + (d['a'] - 1.3) ** 2 + 2 * (d['b'] - 0.7) ** 2}))\n")
    toml = tmp_path / "study.toml"
    toml.write_text('name = "bowl"\nkind = "external"\n'
                    '[variables]\na = { lower = 0.0, upper = 3.0, unit = "mm" }\nb = { lower = 0.0, upper = 2.0, '
                    'unit = "mm" }\n[simulator]\ncommand = ["{python}", "bowl.py"]\noutputs = ["f"]\ntimeout_s = 30\n'
                    '[surrogate]\nn_lines = 4\nsamples_per_line = 7\nmin_samples = 4\nmax_order = 2\n')
    out = tmp_path / "out"
    code = main(["study", str(toml), "--out", str(out), "--workers", "2", "--no-progress", "--lines", "0",
                 "--budget", "80", "--search-points", "20000"])
    assert code == 0, capsys.readouterr()
    result = json.loads((out / "result.json").read_text())
    opt = result["optimum"]
    assert opt["objective"] == pytest.approx(1.0, abs=1e-4)
    assert opt["design"]["a"] == pytest.approx(1.3, abs=0.01) and opt["design"]["b"] == pytest.approx(0.7, abs=0.01)
    assert result["simulations"]["failed"] == 0


def test_ventilator_command_example_matches_the_in_process_engine():
    study = load_study("ventilator-command")
    problem = study.problem
    assert type(problem).__name__ == "ExternalProblem" and problem.names == ("oa", "ab", "bc")
    assert problem.constraints and problem.feasible(study.design("original"))[0]
    x = study.design("original")
    through_command = problem.evaluate(x)
    in_process = load_study("ventilator", {"engine": "exudyn"}).problem.evaluate(x)
    assert through_command["engine"] == "exudyn"
    # The same engine on the same design: equal to the last bit, JSON round trip included.
    assert through_command["t_rms"] == in_process["t_rms"] and through_command["t_max"] == in_process["t_max"]
    assert np.isfinite(through_command["t_rms"])
