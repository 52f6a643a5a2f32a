"""nevergrad's recommended optimizer (NGOpt) and its CMA-ES as budget-limited baselines, driven by ask/tell.

The design is a bounded ``ng.p.Array`` (lower and upper bounds of the box; nevergrad's default bounding, which works
in a standardised space) initialised at a seeded random feasible design and seeded through its ``random_state``;
the optimizer is built with ``budget = problem.budget`` and ``num_workers=1`` and asked for one design at a time
until :class:`CountedProblem` has spent the budget.

* ``nevergrad_ngopt``: ``NGOpt``, nevergrad's documented default ("the optimizer we recommend"), a wizard that picks
  an algorithm from the dimension, budget, bounds and constraints: in a box without constraints (nevergrad 1.0.12) it
  picks SciPy's COBYLA up to 150 calls at 3 variables, a metamodel-assisted CMA-ES
  (``ParametrizedMetaModel(CmaFmin2)``) from 200 to 1500 calls and a portfolio of NGOpt14 instances at 2000; the
  metamodel from 500 calls at 6 to 9 variables and from 700 at 10 to 12.
* ``nevergrad_cma``: ``CMA`` (nevergrad's wrapper of pycma), default population ``4 + 3 ln d`` and step size.

Constraint handling: nevergrad's own cheap-constraint mechanism.  The feasibility test is registered with
``register_cheap_constraint``: ``ask`` resamples (then runs a small constraint-satisfaction search) until the
candidate is feasible, and nevergrad penalises a violating candidate in ``tell``.  A candidate still infeasible
after that is not simulated; it is told :func:`~optimize.baselines.library.rejected_value` (above every simulated
value, growing with the violation), to which nevergrad adds its own penalty.  A failed simulation is told the same
value.

Compatibility shim (nevergrad 1.0.12 under numpy >= 2.4): nevergrad's metamodel step (``learn_on_k_best``, run by
the ``ParametrizedMetaModel`` that NGOpt picks at the budgets above) scores its quadratic model with
``float(model.predict(...))``, a one-element array. numpy deprecated that conversion in 1.25 and made it a
``TypeError`` in 2.4 (nevergrad issues 1612 and 1707); the run died at the first metamodel step, after 13
simulations in 3-D and 80 in 8-D. nevergrad fixed it upstream (``.item()``, PR 1712, March 2026) after its latest
release, 1.0.12. :func:`metamodel_scalar_shim` restores exactly that fix for the duration of one run: it gives
nevergrad's ``metamodel`` module a ``float`` of its own that reads a one-element array's item and is the built-in
``float`` otherwise, and removes it afterwards. Nothing else is changed: NGOpt still chooses its own algorithm, and
no other module (nor numpy) is touched. It is applied only while the installed ``learn_on_k_best`` still has the
defect, so a fixed nevergrad release runs untouched. Capping numpy below 2.4 also works (measured with numpy 2.3.5:
NGOpt spends 300 of 300 in 3-D and 500 of 500 in 8-D) but would cap every environment that installs the ``compare``
extra, the development one included.

Errors: an exception raised by nevergrad is not caught here (it used to be, which hid this defect behind a quietly
short run): it reaches the caller, and ``mechopt compare`` records the run as stopped before its budget, with the
error as its reason.
"""

from __future__ import annotations

import builtins
import importlib
import inspect
import math
import threading
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from types import ModuleType
from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.optimize.baselines.library import rejected_value, require
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["metamodel_needs_shim", "metamodel_scalar_shim", "minimize_nevergrad_cma", "minimize_nevergrad_ngopt"]

#: The statement of nevergrad 1.0.12's ``learn_on_k_best`` that numpy 2.4 rejects (a one-element array to float).
_DEFECT = "float(model.predict("


def _item_float(value: Any = 0.0) -> float:
    """``float`` as numpy < 2.4 had it for nevergrad: a one-element array gives its item (what upstream's fix,
    ``.item()``, does); anything else goes to the built-in ``float`` unchanged."""
    if isinstance(value, np.ndarray) and value.size == 1:
        return builtins.float(value.item())
    return builtins.float(value)


def metamodel_needs_shim(metamodel: ModuleType) -> bool:
    """Whether nevergrad's ``metamodel`` module still converts a one-element array with ``float()``.

    Parameters
    ----------
    metamodel : module
        ``nevergrad.optimization.metamodel``.

    Returns
    -------
    bool
        True when a statement (not a comment) of ``learn_on_k_best`` has the defect, or when its source cannot be
        read (the shim is harmless where it is not needed: it is the built-in ``float`` for everything but a
        one-element array).
    """
    try:
        source = inspect.getsource(metamodel.learn_on_k_best)
    except (OSError, TypeError, AttributeError):
        return True
    return any(_DEFECT in line and not line.lstrip().startswith("#") for line in source.splitlines())


_shim_lock = threading.Lock()
_shim_depth = 0


@contextmanager
def metamodel_scalar_shim() -> Iterator[bool]:
    """Within the block, nevergrad's metamodel reads one-element arrays as numpy < 2.4 let it (see the module doc).

    The ``float`` given to ``nevergrad.optimization.metamodel`` shadows the built-in in that module only and is
    removed when the last nested block exits, even on an error; nothing is left behind.  Nothing is done when the
    installed nevergrad no longer has the defect or the module already has a ``float`` of its own.

    Yields
    ------
    bool
        Whether the shim is in place during the block.
    """
    global _shim_depth
    metamodel = importlib.import_module("nevergrad.optimization.metamodel")
    with _shim_lock:
        applied = _shim_depth > 0 or ("float" not in vars(metamodel) and metamodel_needs_shim(metamodel))
        if applied:
            if _shim_depth == 0:
                metamodel.float = _item_float  # module global: found before the built-in by the module's code
            _shim_depth += 1
    try:
        yield applied
    finally:
        if applied:
            with _shim_lock:
                _shim_depth -= 1
                if _shim_depth == 0:
                    del metamodel.float


class _Feasible:
    """Picklable cheap constraint for nevergrad (it warns about lambdas): True for a feasible design."""

    def __init__(self, problem: CountedProblem) -> None:
        self.problem = problem

    def __call__(self, x: np.ndarray) -> bool:
        return bool(self.problem.feasible(np.asarray(x, dtype=float))[0])


def _run(problem: CountedProblem, seed: int, optimizer_name: str, purpose: str) -> OptimizeResult:
    ng = require("nevergrad", purpose)
    # The start (nevergrad's init, where COBYLA and CMA-ES begin) is a seeded random feasible design, like the starts
    # of the other local baselines: the centre of the box need not be feasible, and a fixed start would make NGOpt's
    # deterministic COBYLA give one result for every seed.
    start = problem.sample_feasible(1, np.random.default_rng(seed))
    if start.shape[0] == 0:
        return problem.result("no feasible start found", nasked=0, nrejected=0)
    parametrization = ng.p.Array(init=start[0], lower=problem.lower.copy(), upper=problem.upper.copy())
    parametrization.random_state = np.random.RandomState(seed)
    if problem.has_constraints:
        parametrization.register_cheap_constraint(_Feasible(problem))
    optimizer = ng.optimizers.registry[optimizer_name](parametrization=parametrization, budget=problem.budget,
                                                      num_workers=1)
    n_asked = n_rejected = 0
    message = "budget spent"
    with warnings.catch_warnings(), metamodel_scalar_shim():
        # Library chatter at every run: nevergrad's "could not bypass the constraint" (handled below), COBYLA's
        # parameter adjustments, pycma's injection notices.
        warnings.simplefilter("ignore")
        try:
            while problem.remaining > 0:
                candidate = optimizer.ask()
                n_asked += 1
                x = np.asarray(candidate.value, dtype=float)
                if not problem.feasible(x)[0]:
                    n_rejected += 1
                    problem.penalised(x)  # counts the proposal, never simulates
                    optimizer.tell(candidate, rejected_value(problem, x))
                    continue
                f = problem.evaluate(x)
                optimizer.tell(candidate, f if math.isfinite(f) else rejected_value(problem, x))
        except BudgetExhausted as exc:
            message = str(exc)
    return problem.result(f"{optimizer_name}: {message}", nasked=n_asked, nrejected=n_rejected)


def minimize_nevergrad_ngopt(problem: CountedProblem, seed: int, **_: Any) -> OptimizeResult:
    """nevergrad's NGOpt wizard with cheap constraints, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the parametrization's random state (all of nevergrad's draws).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nasked``,
        ``nrejected`` (candidates not simulated because infeasible).
    """
    return _run(problem, seed, "NGOpt", "nevergrad_ngopt")


def minimize_nevergrad_cma(problem: CountedProblem, seed: int, **_: Any) -> OptimizeResult:
    """nevergrad's CMA-ES with cheap constraints, until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the parametrization's random state.

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nasked``,
        ``nrejected``.
    """
    return _run(problem, seed, "CMA", "nevergrad_cma")
