"""The table of methods: every record is complete and consistent, options reach any method and an unknown one is
refused in one line, the help lists each method's options, a new baseline (COBYQA) is one function and one record,
and no product module compares a method name as a string."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import mechopt
from mechopt.errors import InputError
from mechopt.optimize.arguments import check_method
from mechopt.optimize.methods import METHODS, Method, check_options, get_method, show_options
from mechopt.studies.benchmark_functions import Branin, Hartmann3

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("name", sorted(METHODS))
def test_every_record_is_complete(name):
    m = METHODS[name]
    assert m.name == name and callable(m.function) and m.summary
    assert 1 <= m.max_objectives <= 4 and isinstance(m.discrete, bool)
    # A method declares discrete variables in its own terms only where a library documents them (or it is ours).
    assert not m.discrete or m.own or m.spends_whole_budget
    assert m.discrete or name != "auto"  # the default searches allowed designs its own way
    assert (m.max_objectives > 1) == (name == "auto")  # only the default takes trade-offs today
    for dim in (2, 3, 4, 8):
        need, rule = m.min_budget(dim, 600, None)
        assert isinstance(need, int) and 3 <= need <= 600 and rule
        assert m.takes_dim(dim) == (m.dims[1] is None or dim <= m.dims[1])
    for option in m.declared:  # every declared default passes its own declaration
        assert option.check(option.default, "") == option.default or option.default is None
    assert m.own or not m.batches  # a baseline proposes one design at a time


def test_the_own_methods_and_their_rules():
    assert [m.name for m in METHODS.values() if m.own] == ["auto", "sparse", "sparse-global"]
    assert METHODS["auto"].min_budget(4, 600, None)[0] == 10  # 2d + 2
    assert METHODS["sparse-global"].min_budget(3, 600, None)[0] == 30  # 10d
    assert METHODS["sparse"].min_budget(3, 600, 2)[0] == 5  # 2 samples on each of 2 lines + 1
    assert [m.name for m in METHODS.values() if m.line_model] == ["sparse"]
    assert {m.compare_name for m in METHODS.values() if m.own} == {"mechopt-auto", "mechopt-sparse", "mechopt-global"}
    with pytest.raises(InputError, match="method 'sparse' handles 2 to 4 design variables; 'p' has 5"):
        check_method("sparse", 5, "p")


def test_an_unknown_option_is_refused_in_one_line_naming_the_methods_options():
    with pytest.raises(InputError) as info:
        mechopt.minimize(Branin(), budget=20, method="slsqp", options={"n_start": 2})
    text = str(info.value)
    assert "\n" not in text
    assert "unknown option 'n_start' of method 'slsqp'; expected one of n_starts, fd_step, ftol, maxiter" in text
    with pytest.raises(InputError, match="unknown option 'n_lines' of method 'auto'; expected one of front"):
        mechopt.minimize(Branin(), budget=20, method="auto", options={"n_lines": 3})
    with pytest.raises(InputError, match="n_starts = 'two': expected int"):
        check_options("slsqp", {"n_starts": "two"})
    with pytest.raises(InputError, match="unknown option bogus; expected one of"):  # the sparse method's own check
        mechopt.minimize(Branin(), budget=30, method="sparse", options={"bogus": 1})


def test_options_reach_any_method(monkeypatch):
    seen = []

    def recording(problem, seed, *, n_designs: int = 4, spread: float = 0.5):
        """A method that records its options.

        Parameters
        ----------
        n_designs : int
            Designs to simulate.
        spread : float
            Ignored.
        """
        seen.append((n_designs, spread))
        for x in problem.sample_feasible(n_designs, np.random.default_rng(seed)):
            problem.evaluate(x)
        return problem.result("done")

    monkeypatch.setitem(METHODS, "recording", Method("recording", recording, "test only"))
    result = mechopt.minimize(Branin(), budget=20, method="recording", options={"n_designs": 7, "spread": 1})
    assert seen == [(7, 1.0)] and result.nfev == 7  # the int given for a float is converted
    assert "n_designs (int, default 4): Designs to simulate" in show_options("recording")
    # A callable takes its keyword-only parameters as options too.
    mechopt.minimize(Branin(), budget=20, method=recording, options={"n_designs": 5})
    assert seen[-1] == (5, 0.5)
    # A baseline of the table gets its options: differential evolution's population changes its run.
    base = mechopt.minimize(Branin(), budget=40, method="differential_evolution", seed=0)
    small = mechopt.minimize(Branin(), budget=40, method="differential_evolution", seed=0, options={"popsize": 3})
    assert base.nfev == small.nfev == 40 and base.fun != small.fun


def test_show_options_lists_every_method_with_its_defaults():
    text = show_options()
    heads = [line.split()[0] for line in text.splitlines() if line and not line.startswith(" ")]
    assert heads == list(METHODS)
    assert "    n_starts (int, default 3): Planned starts" in show_options("cobyqa")
    assert "    search_points (int, default 10000000): grid points of the exhaustive search" in show_options("sparse")
    with pytest.raises(InputError, match="method = 'magic'; expected one of auto, sparse"):
        get_method("magic")


@pytest.mark.parametrize(("problem", "tol"), [(Branin(), 0.01), (Hartmann3(), 0.3)])
def test_cobyqa_runs_within_its_budget_from_one_record(problem, tol):
    # Seeds 0-4 at 40 simulations: Branin f - f* <= 7.3e-3, Hartmann-3 <= 1.05 (a start in a side basin).
    result = mechopt.minimize(problem, budget=40, method="cobyqa", seed=3)
    assert result.success and result.nfev <= 40 and result.method == "cobyqa"
    assert problem.feasible(result.x)[0] and result.fun - problem.f_min <= tol


def test_no_product_module_compares_a_method_name_as_a_string():
    # Dispatch, checks, the plan and compare read the table; a name compared as a string would be a second table.
    names = "|".join(re.escape(n) for n in ["mechopt", *METHODS, *(m.compare_name for m in METHODS.values()
                                                                      if m.compare_name)])
    pattern = re.compile(rf"\bmethod\w*\s*(==|!=|not in|in)\s*[(\[{{]?\s*[\"']({names})[\"']")
    found = []
    for folder in ("optimize", "runs", "studies", "sim", "surrogate", "report", "cli"):
        for path in (ROOT / folder).rglob("*.py"):
            if path.name == "methods.py" and path.parent.name == "optimize":
                continue
            found += [f"{path.relative_to(ROOT)}:{i}" for i, line in enumerate(path.read_text().splitlines(), 1)
                      if pattern.search(line)]
    assert found == []
