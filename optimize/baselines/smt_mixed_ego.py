"""SMT's mixed-integer EGO: the ``smt_ego`` peer on a problem with discrete variables.

SMT documents mixed variables through a design space (``smt.design_space.DesignSpace`` of ``FloatVariable``,
``IntegerVariable`` and ``OrdinalVariable``) given to the Kriging surrogate of ``smt.applications.EGO``, which then
builds its mixed-integer Kriging (``MixedIntegerContext``, continuous relaxation of the integer and ordinal
coordinates in SMT's "folded" space) and rounds each infill point to the allowed values
(``DesignSpace.correct_get_acting``).  The mapping of each kind of variable: a continuous one is a ``FloatVariable``
on [0, 1] (the unit cube of its range, as the continuous peer), an integer an ``IntegerVariable`` on its bounds, a
drawing grid an ``IntegerVariable`` of its index ``k`` (value ``lower + k step``), a catalogue an
``OrdinalVariable`` of its values (its index, in order).

Configuration as the continuous peer (:mod:`~mechopt.optimize.baselines.smt_ego`) but for the kernel and the infill
search: SMT's default ``KRG(corr="squar_exp")`` with its default ``categorical_kernel=CONT_RELAX`` (SMT refuses the
Matérn kernels with a mixed design space unless the categorical kernel is a scalar encoding, and this space has no
categorical variable to encode), criterion EI, one point per iteration, ``n_doe`` initial designs (distinct feasible
allowed designs drawn uniformly), then ``budget - n_doe`` iterations. Constraint handling, as there, is ours: the
infill maximises EI over feasible allowed designs only. EI is evaluated on ``n_candidates`` of them in one call;
from the best ``n_start`` SLSQP moves the continuous coordinates only (the discrete ones held: a relaxed integer
would be rounded back, and SLSQP on SMT's relaxed coordinates took 1 s of EI calls per start), under the margins,
and an end is kept when it is feasible, new and of higher EI than the best candidate. So every simulated design is
allowed, feasible and new.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult, minimize

from mechopt.optimize.baselines.library import kriging_values, require
from mechopt.optimize.baselines.mixed_space import allowed_feasible, snap, variables_of
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["from_folded", "minimize_smt_mixed_ego", "smt_design_space", "to_folded"]


def smt_design_space(design_space: Any, problem: CountedProblem, seed: int) -> Any:
    """SMT's ``DesignSpace`` of the problem's variables (see the module docstring for the mapping)."""
    out = []
    for v in variables_of(problem):
        if v.kind == "catalogue":
            out.append(design_space.OrdinalVariable([float(c) for c in v.values]))
        elif v.kind == "integer":
            out.append(design_space.IntegerVariable(int(v.lower), int(v.upper)))
        elif v.kind == "grid":
            out.append(design_space.IntegerVariable(0, int(v.count) - 1))
        else:
            out.append(design_space.FloatVariable(0.0, 1.0))
    return design_space.DesignSpace(out, seed=seed)


def to_folded(problem: CountedProblem, X: np.ndarray) -> np.ndarray:
    """Allowed designs (n, d) in SMT's folded coordinates."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    U = np.empty_like(X)
    for j, v in enumerate(variables_of(problem)):
        if v.kind == "catalogue":
            U[:, j] = np.searchsorted(np.asarray(v.values), X[:, j] - 1e-12)
        elif v.kind == "grid":
            U[:, j] = np.round((X[:, j] - v.lower) / v.step)
        elif v.kind == "integer":
            U[:, j] = X[:, j]
        else:
            U[:, j] = (X[:, j] - v.lower) / (v.upper - v.lower)
    return U


def from_folded(problem: CountedProblem, U: np.ndarray) -> np.ndarray:
    """The allowed designs (n, d) of SMT's folded coordinates (rounded to the nearest allowed values)."""
    U = np.atleast_2d(np.asarray(U, dtype=float))
    X = np.empty_like(U)
    for j, v in enumerate(variables_of(problem)):
        if v.kind == "catalogue":
            X[:, j] = np.interp(U[:, j], np.arange(len(v.values)), v.values)
        elif v.kind == "grid":
            X[:, j] = v.lower + U[:, j] * v.step
        elif v.kind == "integer":
            X[:, j] = U[:, j]
        else:
            X[:, j] = v.lower + U[:, j] * (v.upper - v.lower)
    return snap(problem, X)


def discrete_mask(problem: CountedProblem) -> np.ndarray:
    """(d,) bool: the problem's discrete variables."""
    return np.array([v.discrete for v in variables_of(problem)], dtype=bool)


def _polish(problem: CountedProblem, neg_ei: Any, u0: np.ndarray, cont: np.ndarray) -> np.ndarray:
    """SLSQP on the continuous folded coordinates of ``u0`` (the discrete ones held), under the margins."""
    def full(v: np.ndarray) -> np.ndarray:
        u = u0.copy()
        u[cont] = v
        return u

    cons = []
    if problem.has_constraints:
        cons.append({"type": "ineq", "fun": lambda v: problem.margins(from_folded(problem, full(v))[0])})
    res = minimize(lambda v: neg_ei(full(v)), u0[cont], method="SLSQP", bounds=[(0.0, 1.0)] * int(cont.sum()),
                   constraints=cons, options={"maxiter": 100})
    return full(np.clip(res.x, 0.0, 1.0))


def _mixed_constrained_ego(ego_class: type, problem: CountedProblem, rng: np.random.Generator,
                           n_candidates: int) -> type:
    """Subclass of SMT's EGO whose infill maximises EI over the feasible allowed designs only."""

    class MixedConstrainedEGO(ego_class):  # type: ignore[misc, valid-type]
        def _find_best_point(self, x_data=None, y_data=None, enable_tunneling=False):  # noqa: ANN001, ANN202
            self._train_gpr(x_data, y_data)
            simulated = from_folded(problem, x_data)
            known = {x.tobytes() for x in simulated}

            def ei(U: np.ndarray) -> np.ndarray:
                return np.ravel(self.EI(np.atleast_2d(U), enable_tunneling, x_data))

            cands = allowed_feasible(problem, n_candidates, rng, exclude=simulated)
            if cands.shape[0] == 0:
                raise BudgetExhausted("no feasible allowed design left to propose")
            C = to_folded(problem, cands)
            values = ei(C)
            best_u, best_val = C[int(np.argmax(values))], float(np.max(values))
            cont = ~discrete_mask(problem)
            for u0 in C[np.argsort(-values, kind="stable")[: self.options["n_start"]]] if cont.any() else ():
                u = _polish(problem, lambda u: -float(ei(u)[0]), u0, cont)
                x = from_folded(problem, u)[0]
                if x.tobytes() in known or not problem.feasible(x)[0]:
                    continue
                value = float(ei(u)[0])
                if value > best_val:
                    best_u, best_val = u, value
            return np.atleast_2d(best_u), True

    return MixedConstrainedEGO


def minimize_smt_mixed_ego(problem: CountedProblem, seed: int, *, n_doe: int | None = None, n_start: int = 5,
                           n_candidates: int = 1000, corr: str = "squar_exp",
                           krg_options: dict[str, Any] | None = None) -> OptimizeResult:
    """SMT's mixed-integer EGO with EI maximised over the feasible allowed designs, ``budget`` simulations.

    Parameters
    ----------
    problem : CountedProblem
        Carries ``variables`` whose kinds decide SMT's design space.
    seed : int
        Seed of the initial design, the infill candidates and SMT's own draws.
    n_doe : int, optional
        Initial designs, default ``max(d + 1, min(10, budget // 4))``.
    n_start : int, default 5
        SLSQP starts of each infill search: the candidates of largest expected improvement.
    n_candidates : int, default 1000
        Feasible allowed designs on which the expected improvement is evaluated.
    corr : str, default "squar_exp"
        Kriging correlation kernel (SMT's default; an exponential one with a mixed design space).
    krg_options : dict, optional
        Further options of SMT's ``KRG`` (e.g. ``{"n_start": 2}``: fewer starts of its hyperparameter search).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nit``.
    """
    applications = require("smt.applications", "smt_ego")
    models = require("smt.surrogate_models", "smt_ego")
    design_space = require("smt.design_space", "smt_ego")
    threadpoolctl = require("threadpoolctl", "smt_ego")
    rng = np.random.default_rng(seed)
    n0 = max(problem.dim + 1, min(10, problem.budget // 4)) if n_doe is None else int(n_doe)
    X0 = allowed_feasible(problem, min(n0, problem.budget), rng)
    if X0.shape[0] == 0:
        return problem.result("no feasible allowed initial design found", nit=0)
    n_iter = problem.budget - X0.shape[0]

    def fun(U: np.ndarray) -> np.ndarray:
        return kriging_values(problem, from_folded(problem, U))

    space = smt_design_space(design_space, problem, seed)
    surrogate = models.KRG(**{"print_global": False, "corr": corr, "design_space": space, "seed": seed,
                              **(krg_options or {})})
    ego = _mixed_constrained_ego(applications.EGO, problem, rng, n_candidates)(
        n_iter=n_iter, criterion="EI", xdoe=to_folded(problem, X0), surrogate=surrogate, n_start=n_start, seed=seed)
    message = f"{n_iter} mixed-integer EGO iterations done"
    with threadpoolctl.threadpool_limits(limits=1):
        try:
            if n_iter > 0:
                ego.optimize(fun=fun)
            else:
                fun(to_folded(problem, X0))
        except BudgetExhausted as exc:
            message = str(exc)
    return problem.result(message, nit=n_iter)
