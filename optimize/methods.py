"""The table of methods: one record per method :func:`mechopt.minimize` accepts, and the checks and help read from it.

As scipy's ``MINIMIZE_METHODS`` and Optuna's samplers: this table says which methods exist and what each takes (its
dimensions, its least budget, whether it proposes batches, how many objectives, whether discrete variables, its
declared options).  :func:`mechopt.minimize`, the argument checks, a study's plan, ``mechopt compare`` and
``mechopt methods`` all read it, so a new method is one function and one record here.  A baseline's options are the
keyword-only parameters of its function (default, type hint and docstring).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from mechopt.errors import InputError
from mechopt.optimize import baselines as bl
from mechopt.optimize.auto.plan import min_budget as auto_min_budget
from mechopt.optimize.baselines.smt_ego import max_budget as ego_max_budget
from mechopt.optimize.method_runs import MethodCall, run_auto, run_baseline, run_sparse, run_sparse_global
from mechopt.optimize.objectives import MAX_OBJECTIVES
from mechopt.optimize.options import Option, options_of
from mechopt.optimize.result import OptimizeResult
from mechopt.optimize.sparse.options import SparseOptions

__all__ = ["AUTO_METHOD", "DEFAULT_METHOD", "METHODS", "MIN_BUDGET", "Method", "available_methods", "check_options",
           "custom_method", "get_method", "show_options"]

#: The fewest simulations any method is given: a model needs a few designs before it can propose one.
MIN_BUDGET = 3
#: The default method of :func:`mechopt.minimize` (:mod:`mechopt.optimize.auto`): its plan follows d and the budget.
AUTO_METHOD = "auto"
#: The method of :func:`mechopt.minimize` and of a study that names none.
DEFAULT_METHOD = AUTO_METHOD

#: ``min_budget(dim, budget, n_lines) -> (simulations, the rule in words)``.
MinBudget = Callable[[int, int, "int | None"], tuple[int, str]]


def _any_budget(dim: int, budget: int, n_lines: int | None) -> tuple[int, str]:
    return MIN_BUDGET, str(MIN_BUDGET)


@dataclass(frozen=True)
class Method:
    """One method of :func:`mechopt.minimize`.

    Attributes
    ----------
    name : str
        What ``method=`` and ``--method`` call it.
    function : callable
        A baseline ``f(counted_problem, seed, **options) -> OptimizeResult`` run one design at a time on a
        :class:`~mechopt.optimize.budget.CountedProblem`; for mechopt's own methods (``own``) a runner
        ``f(call: MethodCall) -> OptimizeResult`` on the sampler.
    summary : str
        One line: the algorithm, its reference, how it treats constraints.
    own : bool
        mechopt's own method (runs on the sampler, proposes designs in batches when ``batches``).
    dims : (int, int or None)
        Fewest and most design variables it takes (None: any number).
    min_budget : callable
        ``(dim, budget, n_lines) -> (simulations, rule)``: the least budget it is given.
    batches : bool
        Whether it proposes as many designs at once as there are workers (else one at a time).
    max_objectives : int
        Most objectives it minimises at once.
    discrete : bool
        Whether it searches discrete variables (grids, integers, catalogues) its own way: the default method's
        acquisition over allowed designs, a library's integer and categorical parameters.  Every method is given
        allowed designs only (the sampler snaps each proposal before it is simulated); the others see a relaxed box.
    options : tuple of Option, optional
        Its declared options; None: the keyword-only parameters of ``function``.
    line_model : bool
        Whether it samples the line plan of :class:`SparseOptions` (its stages are counted in advance and held-out
        lines validate its model).
    starts_from_x0 : bool
        Whether it fits its model to the designs of ``x0`` (else they are simulated before it runs).
    spends_whole_budget : bool
        Whether it asks for designs until the budget is spent (a maintained library's loop): a run that ends with
        simulations left stopped on an error.
    max_budget : callable, optional
        ``dim -> simulations``: the largest budget ``mechopt compare`` gives it (a method whose steps refit a model on
        every sample grows too slow beyond); None: no limit.
    compare_name : str, optional
        Its name in ``mechopt compare`` (mechopt's own: ``mechopt-auto``...); None: ``name``.
    """

    name: str
    function: Callable[..., OptimizeResult]
    summary: str
    own: bool = False
    dims: tuple[int, int | None] = (1, None)
    min_budget: MinBudget = _any_budget
    batches: bool = False
    max_objectives: int = 1
    discrete: bool = False
    options: tuple[Option, ...] | None = None
    line_model: bool = False
    starts_from_x0: bool = False
    spends_whole_budget: bool = False
    max_budget: Callable[[int], int] | None = None
    compare_name: str | None = None

    @property
    def declared(self) -> tuple[Option, ...]:
        """Its options: declared in the record, or the keyword-only parameters of its function."""
        return self.options if self.options is not None else options_of(self.function)

    def takes_dim(self, dim: int) -> bool:
        """Whether it takes ``dim`` design variables."""
        low, high = self.dims
        return dim >= low and (high is None or dim <= high)

    def dims_text(self) -> str:
        """Its dimensions in words."""
        low, high = self.dims
        return f"{low} or more" if high is None else f"{low} to {high}"

    def run(self, call: MethodCall) -> OptimizeResult:
        """Run it on ``call``'s problem within ``call.budget``."""
        return self.function(call) if self.own else run_baseline(call, self.function)


def _sparse_min_budget(dim: int, budget: int, n_lines: int | None) -> tuple[int, str]:
    """Two samples on each line of the global model and one to confirm its candidate: a line plan trimmed to fewer
    would run past the budget (lines: ``n_lines``, or the plan scaled to ``budget``)."""
    lines = int(n_lines) if n_lines is not None else SparseOptions.for_budget(budget, dim).n_lines
    return 2 * lines + 1, f"2 samples on each of its {lines} lines + 1"


def _at_most(limit: int) -> Callable[[int], int]:
    def cap(dim: int) -> int:
        return limit

    return cap


#: The Bayesian baseline refits a Gaussian process on every sample at every step (cubic cost): ``mechopt compare``
#: runs it up to this budget, as the literature uses it for small budgets.
BAYESIAN_MAX_BUDGET = 200
#: Optuna's GPSampler and BoTorch refit their processes at every step: 300 (10-D) takes minutes a run.
GP_PEER_MAX_BUDGET = 300


#: The default method's options (read on trade-offs only: one objective has one acquisition).
_AUTO_OPTIONS = (
    Option("front", "ehvi", str, "acquisition on several objectives: 'ehvi' expected hypervolume improvement, "
           "'parego' ParEGO's random scalarisations", values=("ehvi", "parego")),
)


def _own_records() -> list[Method]:
    """mechopt's own methods: they run on the sampler and propose batches of designs."""
    return [
        Method(AUTO_METHOD, run_auto, "the default (and of every study that names none): Gaussian-process steps "
               "(Matern-5/2, expected improvement): one global model up to 300 designs, restarted trust regions "
               "beyond, or Gauss-Newton runs from multi-level single linkage starts when the problem declares "
               "residuals; failed simulations learned and avoided", own=True, dims=(1, None), batches=True,
               min_budget=lambda dim, budget, n_lines: (auto_min_budget(dim), "2d + 2"), options=_AUTO_OPTIONS,
               starts_from_x0=True, compare_name="mechopt-auto", max_objectives=MAX_OBJECTIVES, discrete=True),
        Method("sparse", run_sparse, "paper 002's line model: lines sampled, fitted by sums of exponentials, blended "
               "by Chebyshev interpolation, searched exhaustively, refined on the simulator (smooth landscapes)",
               own=True, dims=(2, 4), batches=True, min_budget=_sparse_min_budget, options=SparseOptions.DECLARED,
               line_model=True, compare_name="mechopt-sparse"),
        Method("sparse-global", run_sparse_global, "the same lines and blend made global on multimodal landscapes: "
               "basins of the blend simulated, then steps on the blend corrected by every simulation", own=True,
               dims=(2, 4), batches=True, min_budget=lambda dim, budget, n_lines: (10 * dim, "10d"), options=(),
               compare_name="mechopt-global"),
    ]


def _baseline_records() -> list[Method]:
    """The baselines, one design at a time: the in-house ones, then the maintained libraries' (the optional
    ``compare`` extra), which spend their whole budget."""
    library = dict(spends_whole_budget=True)
    return [
        Method("differential_evolution", bl.minimize_differential_evolution, "scipy differential evolution, "
               "best1bin (Storn & Price 1997); constraints by Lampinen's feasibility rules, infeasible trials never "
               "simulated"),
        Method("dual_annealing", bl.minimize_dual_annealing, "scipy generalised simulated annealing with L-BFGS-B "
               "local search (Xiang et al. 1997); rejection, infeasible visits never simulated"),
        Method("nelder_mead", bl.minimize_nelder_mead, "multistart Nelder-Mead simplex (Nelder & Mead 1965) from "
               "feasible Latin-hypercube starts, budget split; rejection"),
        Method("slsqp", bl.minimize_slsqp, "multistart SLSQP (Kraft 1988), constraints as inequality constraints, "
               "counted forward-difference gradients (the SQP route of paper 003)"),
        Method("cobyqa", bl.minimize_cobyqa, "multistart COBYQA (Ragonneau 2022; scipy), derivative-free trust "
               "regions on quadratic models; constraints as nonlinear constraints, infeasible iterates not "
               "simulated"),
        Method("powell_penalty", bl.minimize_powell_penalty, "Powell's conjugate directions (Powell 1964) with Box's "
               "sin² bound transform and a sequence of quadratic exterior penalties (paper 001)"),
        Method("paper000_hybrid", bl.minimize_paper000_hybrid, "paper 000's hybrid: GA on the dimensions (feasible "
               "initial population, SBX, polynomial mutation, 5 % elitism; λ = 50 quadratic penalty, infeasible "
               "children not simulated), then SLSQP from its 100 best distinct designs"),
        Method("sce_ua", bl.minimize_sce_ua, "shuffled complex evolution (Duan, Sorooshian & Gupta 1992), best of "
               "paper 004; feasible-space rejection with random resampling"),
        Method("bayesian", bl.minimize_bayesian, "Bayesian optimisation, Matérn-5/2 GP with ML-II hyperparameters "
               "and expected improvement (Jones, Schonlau & Welch 1998); infeasible candidates rejected before "
               "simulation", max_budget=_at_most(BAYESIAN_MAX_BUDGET)),
        Method("optuna_tpe", bl.minimize_optuna_tpe, "Optuna's multivariate TPE (Bergstra et al. 2011), ask/tell; "
               "Optuna's constrained TPE (trial.set_constraint), infeasible trials told as pruned, never simulated; "
               "discrete variables by suggest_int / suggest_categorical / suggest_float(step=)", discrete=True,
               **library),
        Method("optuna_cmaes", bl.minimize_optuna_cmaes, "Optuna's CMA-ES sampler (Hansen & Ostermeier 2001), "
               "ask/tell; it ignores constraints: infeasible trials not simulated, told a penalty above every "
               "simulated value", **library),
        Method("smt_ego", bl.minimize_smt_ego, "SMT's EGO, Matérn-5/2 Kriging + expected improvement (Jones et al. "
               "1998); infill maximises EI under the margins (SLSQP), only feasible designs simulated; discrete "
               "variables by SMT's mixed-integer EGO (IntegerVariable / OrdinalVariable design space)",
               max_budget=ego_max_budget, discrete=True, **library),
        Method("pymoo_ga", bl.minimize_pymoo_ga, "pymoo GA, SBX + polynomial mutation, elitist survival (Deb 2001); "
               "feasibility-first tournament and survival (Deb 2000), infeasible designs not simulated; discrete "
               "variables by pymoo's MixedVariableGA (Real / Integer / Choice)", discrete=True, **library),
        Method("pymoo_pso", bl.minimize_pymoo_pso, "pymoo adaptive PSO (Zhan et al. 2009); feasibility-first "
               "personal/global bests, infeasible designs not simulated", **library),
        Method("pymoo_de", bl.minimize_pymoo_de, "pymoo DE/best/1/bin, F 0.5, CR 0.9 (Storn & Price 1997); "
               "feasibility-first replacement, infeasible designs not simulated", **library),
        Method("nevergrad_ngopt", bl.minimize_nevergrad_ngopt, "nevergrad's recommended NGOpt wizard (COBYLA at 3 "
               "variables and <= 150 calls); nevergrad's cheap-constraint resampling, leftovers penalised, not "
               "simulated", **library),
        Method("nevergrad_cma", bl.minimize_nevergrad_cma, "nevergrad's CMA-ES (pycma); nevergrad's cheap-constraint "
               "resampling, leftovers penalised, not simulated", **library),
        Method("py_bobyqa", bl.minimize_py_bobyqa, "Py-BOBYQA (Cartis et al. 2019; Powell's BOBYQA), quadratic models "
               "on 2d + 1 points in a trust region, its own restarts; infeasible iterates continued from the last "
               "feasible one, not simulated", **library),
        Method("optuna_gp", bl.minimize_optuna_gp, "Optuna's GPSampler, Matern-5/2 ARD process and log expected "
               "improvement, ask/tell (gp-peers extra); Optuna's constraint models, infeasible trials told a "
               "penalty, not simulated", max_budget=_at_most(GP_PEER_MAX_BUDGET), **library),
        Method("botorch_qlognei", bl.minimize_botorch_qlognei, "BoTorch's qLogNoisyExpectedImprovement (Ament et al. "
               "2023) on SingleTaskGP, BoTorch's own loop (gp-peers extra); margins modelled as outputs, infeasible "
               "proposals not simulated", max_budget=_at_most(GP_PEER_MAX_BUDGET), **library),
    ]


#: Every method by name, in the order of :func:`available_methods`.
METHODS: dict[str, Method] = {m.name: m for m in [*_own_records(), *_baseline_records()]}


def available_methods() -> list[str]:
    """Every method name :func:`mechopt.minimize` and ``mechopt study --method`` accept."""
    return list(METHODS)


def custom_method(fn: Callable[..., OptimizeResult]) -> Method:
    """The record of a user's callable ``f(counted_problem, seed, **options)``: a baseline named after it."""
    return Method(getattr(fn, "__name__", "custom"), fn, "a callable of the user")


def get_method(method: str | Callable[..., OptimizeResult]) -> Method:
    """The record of a method name (or of a user's callable), or a one-line :class:`InputError`."""
    if callable(method):
        return custom_method(method)
    if method not in METHODS:
        raise InputError(f"method = {method!r}; expected one of {', '.join(METHODS)} or a callable")
    return METHODS[method]


def check_options(method: str | Callable[..., OptimizeResult], options: Mapping[str, Any] | None) -> dict[str, Any]:
    """A method's options, checked against its declaration (as scipy's ``_check_unknown_options``).

    Parameters
    ----------
    method : str or callable
        A name of :data:`METHODS` or a user's callable.
    options : mapping, optional
        Values by name.

    Returns
    -------
    dict
        The given values, converted where declared (an int for a float); defaults are the method's own.

    Raises
    ------
    InputError
        One line: an unknown option (with the method's options listed) or an ill-typed value.
    """
    record = get_method(method)
    declared = {o.name: o for o in record.declared}
    given = dict(options or {})
    unknown = sorted(set(given) - set(declared))
    if unknown:
        takes = f"expected one of {', '.join(declared)}" if declared else "it takes none"
        raise InputError(f"unknown option {unknown[0]!r} of method {record.name!r}; {takes} "
                         f"(`mechopt methods {record.name}`)")
    return {name: declared[name].check(value, f"method {record.name!r}: ") for name, value in given.items()}


def _option_line(option: Option) -> str:
    kinds = option.types if isinstance(option.types, tuple) else (option.types,)
    kind = " or ".join(t.__name__ for t in kinds) + (" or None" if option.nullable else "")
    return f"    {option.name} ({kind}, default {option.default!r}): {option.desc}"


def show_options(method: str | None = None) -> str:
    """The documentation of a method's options, or of every method's (as scipy's ``show_options``).

    Parameters
    ----------
    method : str, optional
        A name of :data:`METHODS`; None: every method.

    Returns
    -------
    str
        Per method: a line with its name and summary, then indented its dimensions, least budget, batches and
        objectives, and one line per option with its type, default and description.
    """
    records = [get_method(method)] if method is not None else list(METHODS.values())
    blocks = []
    for m in records:
        need = m.min_budget(3, 600, None)[1]
        head = (f"{m.name}  {m.summary}\n  takes {m.dims_text()} variables, budget >= {need}, "
                f"{'batches of designs' if m.batches else 'one design at a time'}, {m.max_objectives} "
                f"objective{'s' if m.max_objectives > 1 else ''}{', discrete variables' if m.discrete else ''}")
        lines = [_option_line(o) for o in m.declared]
        blocks.append("\n".join([head, "  options:" if lines else "  options: none", *lines]))
    return "\n".join(blocks)
