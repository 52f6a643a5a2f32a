"""Budget-counted black-box problem shared by every baseline optimizer.

:class:`CountedProblem` wraps the expensive objective (one call = one motion simulation) and the cheap constraint
margins (kinematics, not counted).  It is the only door to the simulator: it counts the calls, refuses the call that
would exceed the budget by raising :class:`BudgetExhausted`, and remembers the best *feasible* design seen, so a
method interrupted at any point still returns a valid answer.

Two constraint schemes are offered to the methods:

* rejection -- :meth:`CountedProblem.penalised` with ``reject=True``: an infeasible design is never simulated; it gets
  ``infeasible_value + penalty * violation`` so that ranking-based methods still see a slope back to feasibility;
* exterior penalty -- ``reject=False``: ``objective + penalty * violation**power`` as in the mechanism-synthesis
  papers.  The objective is only called at an infeasible design when the problem was built with
  ``simulate_infeasible=True`` (the simulator is defined there), because a real simulator cannot move a mechanism
  that cannot be assembled; otherwise it is continued from the feasible boundary (:meth:`CountedProblem.extended`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.errors import InputError
from mechopt.optimize.constrained_box import ConstrainedBox

__all__ = ["BudgetExhausted", "CountedProblem", "Evaluation", "run_multistart"]


class BudgetExhausted(RuntimeError):
    """A method asked for a simulation beyond its budget (or for too many cheap proposals).

    Attributes
    ----------
    local : bool
        True when only a temporary sub-budget (:meth:`CountedProblem.sub_budget`) is spent and the global budget still
        has calls left, so a multistart method may go on with its next start.
    """

    def __init__(self, message: str, *, local: bool = False) -> None:
        super().__init__(message)
        self.local = local


@dataclass(frozen=True)
class Evaluation:
    """One simulator call: design, objective value (NaN when the simulation failed) and feasibility."""

    x: np.ndarray
    f: float
    feasible: bool


class CountedProblem(ConstrainedBox):
    """Expensive objective with a hard call budget, cheap constraints and a best-feasible record.

    The box, the constraint margins and feasibility (cheap, not counted) are those of :class:`ConstrainedBox`.

    Parameters
    ----------
    objective : callable
        ``objective(x) -> float`` for a design ``x`` of shape ``(d,)``; every call is counted.
    bounds : sequence of (low, high) pairs or array of shape (d, 2)
        Box of the design space; a design outside the box is infeasible.
    budget : int
        Maximum number of objective calls.
    constraints : callable, optional
        ``constraints(x) -> array`` of margins, feasible when all are ``>= 0``.  Cheap, not counted.
    penalty : float, default 1e3
        Default penalty coefficient of :meth:`penalised` (units of objective per unit of violation).
    infeasible_value : float, default 1e10
        Base value given to a rejected (not simulated) design; must exceed any feasible objective value.
    simulate_infeasible : bool, default False
        Whether the objective may be called at infeasible designs by exterior-penalty methods.
    failure_errors : tuple of exception types, default ()
        Exceptions of the objective meaning "this design cannot be simulated"; such a call is counted and yields NaN.
    cache : bool, default True
        Return the stored value for an exactly repeated design instead of simulating it again.
    max_proposals : int, optional
        Cap on all requests (simulated, cached or rejected), default ``50 * budget + 1000``; it stops methods
        whose proposals are all rejected or cached, which would otherwise never reach the budget.
    vectorized_constraints : bool, default False
        ``constraints`` accepts an array ``(n, d)`` and returns ``(n, m)``; speeds up dense feasibility checks.
    snap : callable, optional
        ``snap(x) -> x'``: the allowed design of a proposal (discrete variables' grids, integers, catalogues).
        Each proposal is moved there before it is keyed and simulated, so two proposals that round alike are one
        simulation (the second one free); give ``constraints`` of the snapped design too, so that a method's
        feasibility test agrees with what is simulated.
    """

    def __init__(
        self,
        objective: Callable[[np.ndarray], float],
        bounds: Sequence[Sequence[float]] | np.ndarray,
        budget: int,
        constraints: Callable[[np.ndarray], np.ndarray] | None = None,
        *,
        penalty: float = 1.0e3,
        infeasible_value: float = 1.0e10,
        simulate_infeasible: bool = False,
        failure_errors: tuple[type[BaseException], ...] = (),
        cache: bool = True,
        max_proposals: int | None = None,
        vectorized_constraints: bool = False,
        snap: Callable[[np.ndarray], np.ndarray] | None = None,
    ) -> None:
        super().__init__(bounds, constraints, vectorized_constraints=vectorized_constraints)
        self._snap = snap
        if int(budget) != budget or budget < 0:
            raise InputError(f"budget must be a non-negative integer, got {budget!r}")
        self._objective = objective
        self.budget = int(budget)
        self.penalty = float(penalty)
        self.infeasible_value = float(infeasible_value)
        self.simulate_infeasible = bool(simulate_infeasible)
        self.failure_errors = tuple(failure_errors)
        self.cache = bool(cache)
        self.max_proposals = 50 * self.budget + 1000 if max_proposals is None else int(max_proposals)
        self.history: list[Evaluation] = []
        self.best_x: np.ndarray | None = None
        self.best_f = math.inf
        self._nfev = 0
        self._nproposals = 0
        self._cap = self.budget
        self._memo: dict[bytes, float] = {}

    @property
    def nfev(self) -> int:
        """Simulator calls made so far."""
        return self._nfev

    @property
    def remaining(self) -> int:
        """Simulator calls left in the global budget."""
        return self.budget - self._nfev

    @property
    def available(self) -> int:
        """Simulator calls left in the current sub-budget (the global remainder outside any)."""
        return self._cap - self._nfev

    @property
    def nproposals(self) -> int:
        """All requests so far: simulated, cached and rejected ones."""
        return self._nproposals

    def _propose(self) -> None:
        self._nproposals += 1
        if self._nproposals > self.max_proposals:
            raise BudgetExhausted(f"proposal limit {self.max_proposals} reached after {self._nfev} simulations")

    def evaluate(self, x: np.ndarray) -> float:
        """Objective of one design, counted against the budget (cached designs are free).

        Parameters
        ----------
        x : ndarray, shape (d,)

        Returns
        -------
        float
            Objective value, NaN when the simulation failed with one of ``failure_errors``.

        Raises
        ------
        BudgetExhausted
            When the (sub-)budget is spent; the objective is then not called.
        """
        x = np.array(x, dtype=float).reshape(self.dim)
        if self._snap is not None:
            x = np.array(self._snap(x), dtype=float).reshape(self.dim)
        self._propose()
        key = x.tobytes()
        if self.cache and key in self._memo:
            return self._memo[key]
        if self._nfev >= self._cap:
            local = self._nfev < self.budget
            raise BudgetExhausted(
                f"{'sub-' if local else ''}budget exhausted after {self._nfev} simulations", local=local
            )
        self._nfev += 1
        try:
            f = float(self._objective(x.copy()))
        except self.failure_errors:
            f = math.nan
        feasible = bool(self.feasible(x)[0])
        self.history.append(Evaluation(x, f, feasible))
        if feasible and math.isfinite(f) and f < self.best_f:
            self.best_f, self.best_x = f, x.copy()
        # Filled even without caching: extended() reads the value of an anchor it has already paid for.
        self._memo[key] = f
        return f

    __call__ = evaluate

    def extended(self, x: np.ndarray, anchor: np.ndarray | None = None) -> float:
        """Objective continued beyond the feasible region without simulating an infeasible design.

        At a feasible ``x`` this is the objective.  At an infeasible ``x`` it is the objective itself when the problem
        allows ``simulate_infeasible``; otherwise, with a feasible ``anchor``, the secant continuation along the ray
        anchor → x: ``f(p) + (f(p) - f(anchor)) / |p - anchor| * |x - p|`` with ``p`` the last feasible point of
        the ray (one simulation, of the feasible ``p``; distances in unit-cube coordinates).  It is continuous and
        keeps the slope the objective had when the ray left the feasible region, so a penalty method can cross the
        boundary as it would with a simulator defined everywhere.

        Parameters
        ----------
        x : ndarray, shape (d,)
        anchor : ndarray, shape (d,), optional
            Feasible design, normally one already simulated (its value is then reused for free).

        Returns
        -------
        float
            NaN when the simulation failed or no continuation is possible (infeasible ``x`` without anchor).
        """
        x = np.asarray(x, dtype=float)
        if self.simulate_infeasible or self.feasible(x)[0]:
            return self.evaluate(x)
        if anchor is None or not self.feasible(anchor)[0]:
            return math.nan
        anchor = np.asarray(anchor, dtype=float)
        p = self.boundary_point(anchor, x)
        fp = self.evaluate(p)
        known = self._memo.get(anchor.tobytes())
        fa = known if known is not None else self.evaluate(anchor)
        run = float(np.linalg.norm(self.to_unit(p) - self.to_unit(anchor)))
        if run <= 1e-12 or not (math.isfinite(fa) and math.isfinite(fp)):
            return fp
        return fp + (fp - fa) / run * float(np.linalg.norm(self.to_unit(x) - self.to_unit(p)))

    def penalised(
        self,
        x: np.ndarray,
        *,
        reject: bool = True,
        penalty: float | None = None,
        power: float = 1.0,
        anchor: np.ndarray | None = None,
    ) -> float:
        """Objective with the constraint handling of the calling method.

        Parameters
        ----------
        x : ndarray, shape (d,)
        reject : bool, default True
            Rejection: an infeasible design is not simulated and gets ``infeasible_value + penalty * v**power``.
            With False (exterior penalty) it gets ``extended(x, anchor) + penalty * v**power`` (see
            :meth:`extended`; the rejection value when no continuation is possible).
        penalty : float, optional
            Penalty coefficient, default the problem's ``penalty``.
        power : float, default 1
            Exponent of the violation (2 for the quadratic exterior penalty of the literature).
        anchor : ndarray, shape (d,), optional
            Feasible design from which an infeasible ``x`` is continued (exterior penalty only).

        Returns
        -------
        float
            Never NaN: a failed simulation is mapped to the rejection value so comparisons stay well defined.
        """
        v = self.violation(x)
        if v == 0.0:
            f = self.evaluate(x)
            return f if math.isfinite(f) else self.infeasible_value
        term = (self.penalty if penalty is None else penalty) * v**power
        if reject or not (self.simulate_infeasible or anchor is not None):
            self._propose()
            return self.infeasible_value + term
        f = self.extended(x, anchor)
        return (f if math.isfinite(f) else self.infeasible_value) + term

    @contextmanager
    def sub_budget(self, n: int) -> Iterator[None]:
        """Temporarily allow at most ``n`` more simulations (a multistart method's share).

        Parameters
        ----------
        n : int
            Calls allowed inside the ``with`` block (clipped to the global remainder).
        """
        previous = self._cap
        self._cap = min(previous, self._nfev + max(0, int(n)))
        try:
            yield
        finally:
            self._cap = previous

    def best_designs(self, k: int, *, min_distance: float = 1e-3) -> np.ndarray:
        """The ``k`` best feasible simulated designs, mutually apart by ``min_distance`` in the unit cube.

        Parameters
        ----------
        k : int
        min_distance : float, default 1e-3

        Returns
        -------
        ndarray, shape (<= k, d)
        """
        good = [e for e in self.history if e.feasible and math.isfinite(e.f)]
        good.sort(key=lambda e: e.f)
        chosen: list[np.ndarray] = []
        for e in good:
            u = self.to_unit(e.x)
            if all(np.linalg.norm(u - self.to_unit(c)) >= min_distance for c in chosen):
                chosen.append(e.x)
            if len(chosen) == k:
                break
        return np.array(chosen).reshape(-1, self.dim)

    def result(self, message: str, **extra: object) -> OptimizeResult:
        """Result of a method: best feasible simulated design, calls used, message.

        Parameters
        ----------
        message : str
            Why the method stopped.
        **extra
            Method-specific fields added to the result.

        Returns
        -------
        scipy.optimize.OptimizeResult
            ``x`` (NaN array when no feasible design was simulated), ``fun`` (inf then), ``nfev``, ``success``
            (a feasible design was found), ``message``, ``nproposals``.
        """
        found = self.best_x is not None
        return OptimizeResult(
            x=self.best_x.copy() if found else np.full(self.dim, np.nan),
            fun=self.best_f,
            nfev=self._nfev,
            success=found,
            message=message if found else f"{message}; no feasible design simulated",
            nproposals=self._nproposals,
            **extra,
        )


def run_multistart(
    problem: CountedProblem,
    starts: np.ndarray,
    local_run: Callable[[np.ndarray], object],
    *,
    rng: np.random.Generator | None = None,
    max_starts: int = 1000,
    min_share: int = 1,
) -> tuple[int, str]:
    """Run a local method from several starts, splitting the remaining budget between them.

    Start ``k`` of ``n`` may use ``ceil(remaining / (n - k))`` simulations, so what a converged start leaves goes to
    the later ones.  When the planned starts are done and budget is left, fresh feasible Latin-hypercube starts are
    drawn (with ``rng``) and each gets all that is left, so a fast-converging method still spends its budget.

    Parameters
    ----------
    problem : CountedProblem
    starts : ndarray, shape (n, d)
        Planned feasible starts.
    local_run : callable
        ``local_run(x0)`` runs one local search; it may raise :class:`BudgetExhausted`.
    rng : numpy.random.Generator, optional
        Source of the extra starts; without it no extra start is drawn.
    max_starts : int, default 1000
        Cap on the total number of starts.
    min_share : int, default 1
        Stop when fewer calls than this are left (a local search needs a few calls to do anything).

    Returns
    -------
    n_started : int
        Number of local searches run.
    message : str
        Why the loop stopped.
    """
    queue = [np.asarray(s, dtype=float) for s in starts]
    n_planned = len(queue)
    k = 0
    while k < max_starts and problem.remaining >= min_share:
        if k >= len(queue):
            extra = problem.sample_feasible(1, rng) if rng is not None else np.zeros((0, problem.dim))
            if extra.shape[0] == 0:
                return k, f"{k} starts done, no further feasible start"
            queue.append(extra[0])
        share = math.ceil(problem.remaining / max(1, n_planned - k))
        try:
            with problem.sub_budget(share):
                local_run(queue[k])
        except BudgetExhausted as exc:
            if not exc.local:
                return k + 1, str(exc)
        k += 1
    return k, f"{k} starts done, {problem.remaining} simulations left"
