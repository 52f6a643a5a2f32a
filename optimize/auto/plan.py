"""The plan of the default method, chosen from the budget and the problem's declaration (and said in the result).

* ``global`` (any number of variables): one GP over the whole box, expected-improvement steps, then a local polish
  on the model around the incumbent for the last tenth of the budget (EGO, Jones et al. 1998).  A budget above
  ``GLOBAL_MAX_POINTS`` continues from there in trust regions around the incumbent, which grow and shrink with
  success and restart at the global model's most promising point when one collapses (TuRBO, Eriksson et al. 2019);
  the last tenth of the budget then minimises the local model's mean around the best design of any restart.  In
  the trust regions a batch of several designs a step is the minimisers of as many posterior draws (Thompson
  sampling, TuRBO's choice): the kriging believer spreads a batch to the region's corners.

  From 5 variables up the trust regions used to start at the Sobol design, on the argument that a global GP in
  many variables is mostly uncertainty and its expected improvement runs to the box's corners.  With the model as
  it is now (a constant mean by generalised least squares, the additive component) that no longer holds: measured
  with ``auto_search``, median gap % of the range, 10 seeds, trust regions from the start -> the global model:
  Hartmann-6 at 60 0.0028 -> 0.0001, Levy-8 at 100 0.97 -> 0.40, Ackley-8 at 100 27.3 -> 11.4, and on landscapes
  outside the suite Michalewicz-5 at 40 53.2 -> 21.5 and at 100 6.7 -> 0.89, Ackley-12 at 150 (5 seeds) 59.4 ->
  17.6, Rosenbrock-10 at 150 0.0088 -> 0.0039; Rosenbrock-6 at 60, Griewank-8 at 200, Rastrigin-6 at 150,
  Zakharov-8 at 200 and Hartmann-3 hidden in 10 variables the same; worse: Levy-12 at 150 1.0 -> 2.0 (5 seeds),
  Branin hidden in 12 variables 0.0000 -> 0.0001.  What the trust regions do better is refine a sharp minimum with
  hundreds of simulations (``benchmarks/bench_default.py``, Ackley-8 at 500: 0.0174 -> 0.159 %, both far below
  every peer's 4 % and more), and they now take over from the 300th design instead of from the Sobol design.

* ``least-squares`` (any d, when the problem declares residuals): Gauss-Newton runs on the residuals from the
  starts that multi-level single linkage picks in a growing Sobol sample (:mod:`mechopt.optimize.least_squares`).
  The residuals' Jacobian is a better local model than any GP of their sum, and the sample needs no model at all.

Both start from a scrambled Sobol design of 2d + 2 points (fewer when the budget is short, so that at least a
quarter of it is left to the model): the smallest design that fixes a length-scale per variable with some margin.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Plan", "choose_plan", "min_budget"]

#: Most designs the global GP is fitted to; the rest of a larger budget goes to restarted trust regions.  A fit costs
#: n³ (0.1 s of the method's own time a simulation at 300 designs, 0.22 s at 600, hours beyond a few thousand), and
#: by then the designs have found the promising basins: what is left is local, and the trust regions' restarts take
#: the search elsewhere when a region is exhausted.
GLOBAL_MAX_POINTS = 300


def min_budget(dim: int) -> int:
    """The fewest simulations the default method accepts: 2d + 2."""
    return 2 * dim + 2


@dataclass(frozen=True)
class Plan:
    """What the default method will do.

    Attributes
    ----------
    name : str
        ``"global"`` or ``"least-squares"``.
    n_init : int
        Space-filling designs simulated first.
    n_polish : int
        Last simulations spent on the local polish (global plan).
    batch : int
        Designs proposed per step.
    """

    name: str
    n_init: int
    n_polish: int
    batch: int

    def describe(self, dim: int, budget: int) -> str:
        """One line for the result's message."""
        if self.name == "least-squares":
            what = "Gauss-Newton runs on the residuals from multi-level single linkage starts"
        else:
            what = "one global GP, expected improvement"
            if budget > GLOBAL_MAX_POINTS:
                what += f" up to {GLOBAL_MAX_POINTS} designs, then a restarted trust region"
                if self.batch > 1:
                    what += f" (Thompson-sampled batches of {self.batch})"
            what += f", local polish of the last {self.n_polish}"
        return f"plan {self.name} (d = {dim}, budget {budget}): {self.n_init} Sobol designs, then {what}"


def choose_plan(dim: int, budget: int, batch: int = 1, least_squares: bool = False) -> Plan:
    """The plan for ``dim`` variables and ``budget`` simulations, ``batch`` designs a step; ``least_squares``: the
    problem declares residuals."""
    n_init = min(2 * dim + 2, budget - max(1, budget // 4))
    if least_squares:
        return Plan("least-squares", n_init, 0, batch)
    n_polish = max(1, budget // 10) if budget - n_init > 2 else 0
    return Plan("global", n_init, n_polish, batch)
