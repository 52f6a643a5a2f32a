"""The command line lists what mechopt ships, chooses a method, and refuses what the API refuses, with the API's
own one-line messages."""

import json

import numpy as np
import pytest

import mechopt
from mechopt.cli.main import EXIT_ERROR, main
from mechopt.errors import InputError
from mechopt.optimize.arguments import available_methods
from mechopt.studies.benchmark_functions import Hartmann3
from mechopt.studies.catalogue import available_studies


def test_version(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"mechopt {mechopt.__version__}"


def test_studies_lists_every_study_and_test_function_with_a_description(capsys):
    assert main(["studies"]) == 0
    lines = capsys.readouterr().out.splitlines()
    listed = {line.split()[0]: line for line in lines if line.strip() and not line.startswith("run one")}
    assert set(listed) == set(available_studies())
    assert "four-bar, 3 variables: Emergency ventilator" in listed["ventilator"]
    assert "test function, 3 variables: Hartmann-3" in listed["hartmann3"]


def test_methods_lists_every_method_with_its_options(capsys):
    assert main(["methods"]) == 0
    out = capsys.readouterr().out
    heads = [line for line in out.splitlines() if line.strip() and not line.startswith((" ", "choose"))]
    assert [line.split()[0] for line in heads] == available_methods()
    assert all(len(line.split(None, 1)) == 2 for line in heads)  # each has a description
    assert "    n_starts (int, default 5): Planned starts" in out  # slsqp's option, with its default
    assert main(["methods", "cobyqa"]) == 0
    one = capsys.readouterr().out
    assert one.startswith("cobyqa  ") and "initial_tr_radius (float, default 0.25)" in one
    assert main(["methods", "magic"]) == 1
    assert "method = 'magic'; expected one of auto" in capsys.readouterr().err


def test_study_runs_a_chosen_method(tmp_path, capsys):
    out = tmp_path / "h3"
    assert main(["study", "hartmann3", "--method", "differential_evolution", "--budget", "40", "--lines", "0",
                 "--workers", "1", "--no-progress", "--out", str(out)]) == 0
    result = json.loads((out / "result.json").read_text())
    assert result["problem"]["method"] == "differential_evolution"
    assert result["simulations"]["optimisation"] == 40
    assert result["optimum"]["predicted"] is None  # no line model behind this method
    # The same call through the API gives the same answer (same seed, same budget).
    api = mechopt.minimize(Hartmann3(), budget=40, method="differential_evolution", seed=0)
    assert result["optimum"]["objective"] == pytest.approx(api.fun, rel=0, abs=0)
    assert "method differential_evolution" in capsys.readouterr().out


def test_study_starts_from_x0_as_the_api_does(tmp_path, capsys):
    out = tmp_path / "h3"
    x0 = [[0.1, 0.55, 0.85], [0.2, 0.5, 0.8]]
    assert main(["study", "hartmann3", "--method", "auto", "--budget", "12", "--x0", "0.1,0.55,0.85", "--x0",
                 "0.2,0.5,0.8", "--lines", "0", "--workers", "1", "--no-progress", "--out", str(out)]) == 0
    result = json.loads((out / "result.json").read_text())
    assert result["simulations"]["optimisation"] == 12  # x0 counts in the budget
    api = mechopt.minimize(Hartmann3(), budget=12, method="auto", seed=0, x0=x0)
    assert result["optimum"]["objective"] == pytest.approx(api.fun, rel=0, abs=0)
    assert api.fun <= Hartmann3().function(np.array(x0)).min() + 1e-12  # never worse than x0
    printed = capsys.readouterr().out
    assert "x0: 2 design(s) simulated first, counted in the budget of 12 (the method has 10)" in printed
    assert "6 Sobol designs" in printed and "after the 2 designs of x0" in printed


@pytest.mark.parametrize(("argv", "call"), [
    (["--budget", "1"], {"budget": 1}),
    (["--method", "no_such_method"], {"method": "no_such_method"}),
    (["--x0", "0.1,0.2"], {"x0": [0.1, 0.2]}),
    (["--x0", "1.5,0.5,0.5"], {"x0": [1.5, 0.5, 0.5]}),
])
def test_cli_and_api_refuse_the_same_arguments_with_the_same_message(tmp_path, capsys, argv, call):
    code = main(["study", "hartmann3", "--lines", "0", "--no-progress", "--out", str(tmp_path / "x"), *argv])
    assert code == EXIT_ERROR
    cli_message = capsys.readouterr().err.strip().removeprefix("mechopt: error: ")
    with pytest.raises(InputError) as api:
        mechopt.minimize(Hartmann3(), **{"budget": 30, **call})
    assert cli_message == str(api.value)
    assert not (tmp_path / "x" / "samples.sqlite").exists()  # refused before any simulation


def test_a_line_model_method_refuses_more_than_four_variables_in_cli_terms():
    from mechopt.optimize.arguments import check_method

    with pytest.raises(InputError, match="handles 2 to 4 design variables; 'p6' has 6"):
        check_method("sparse", 6, "p6")


def test_test_function_descriptions_are_whole_sentences_without_markup():
    # The first docstring line cut failing_hartmann3's sentence in two and kept its ``evaluate``.
    from mechopt.studies.benchmark_functions import SUITE
    from mechopt.studies.catalogue import load_study

    for name, cls in SUITE.items():
        text = cls.summary()
        assert text and "``" not in text and "\n" not in text and not text.endswith("."), name
        assert load_study(name).description == text
    assert SUITE["failing_hartmann3"].summary().endswith("returns NaN where x2 > 0.9 (the global minimum lies where it "
                                                          "succeeds)")


def test_init_copies_a_study_that_then_runs_and_refuses_what_it_cannot_copy(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["init", "rowing"]) == 0
    assert sorted(p.name for p in (tmp_path / "my-rowing").iterdir()) == ["README.md", "desired_effort.csv",
                                                                           "study.toml"]
    capsys.readouterr()
    assert main(["study", "my-rowing/study.toml", "--dry-run"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "dry run: nothing simulated"
    assert main(["init", "rowing"]) == EXIT_ERROR  # the folder is not empty: nothing is overwritten
    assert "my-rowing exists and is not an empty folder" in capsys.readouterr().err
    # It listed hartmann3 among the studies it could not find.
    assert main(["init", "hartmann3"]) == EXIT_ERROR
    err = capsys.readouterr().err
    assert "'hartmann3' is a test function (a Python class), not a study file to copy" in err
    assert "hartmann3," not in err and err.count("\n") == 1
    assert main(["init", "../rowing"]) == EXIT_ERROR
    assert "unknown study '../rowing'; expected one of" in capsys.readouterr().err
