"""The plan of the default method, chosen from the number of variables and the budget (and said in the result).

* ``global`` (d <= 4): one GP over the whole box, expected-improvement steps, then a local polish on the model
  around the incumbent for the last tenth of the budget.  In 2 to 4 variables tens of designs cover the box well
  enough for a global model to find the best basin (EGO, Jones et al. 1998).  A budget above
  ``GLOBAL_MAX_POINTS`` continues on the trust-region plan from there.
* ``trust-region`` (d >= 5): expected-improvement steps in a trust region around the incumbent, which grows and
  shrinks with success and restarts at the global model's most promising point when it collapses (TuRBO, Eriksson
  et al. 2019); the last tenth of the budget minimises the local model's mean around the best design of any
  restart (a final polish).  A batch of several designs a step is the minimisers of as many posterior draws
  (Thompson sampling, TuRBO's choice): the kriging believer spreads a batch to the region's corners.

* ``least-squares`` (any d, when the problem declares residuals): Gauss-Newton runs on the residuals from the
  starts that multi-level single linkage picks in a growing Sobol sample (:mod:`mechopt.optimize.least_squares`).
  The residuals' Jacobian is a better local model than any GP of their sum, and the sample needs no model at all.

All start from a scrambled Sobol design of 2d + 2 points (fewer when the budget is short, so that at least a
quarter of it is left to the model): the smallest design that fixes a length-scale per variable with some margin.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Plan", "choose_plan", "min_budget"]

#: Largest number of variables for which one global GP is used.
GLOBAL_MAX_DIM = 4
#: Most designs the global GP is fitted to; the rest of a larger budget goes to the trust-region plan.  A fit costs
#: n³ (0.1 s of the method's own time a simulation at 300 designs, 0.22 s at 600, hours beyond a few thousand), and
#: by then tens of designs per variable have covered a box of 2 to 4 variables: what is left is local, and the trust
#: region's restarts take the search elsewhere when a region is exhausted.
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
        ``"global"``, ``"trust-region"`` or ``"least-squares"``.
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
        elif self.name == "global":
            what = "one global GP, expected improvement"
            if budget > GLOBAL_MAX_POINTS:
                what += f" up to {GLOBAL_MAX_POINTS} designs, then a restarted trust region"
            what += f", local polish of the last {self.n_polish}"
        else:
            steps = (f"Thompson-sampled batches of {self.batch}" if self.batch > 1 else "expected improvement")
            what = f"{steps} in a restarted trust region, local polish of the last {self.n_polish}"
        return f"plan {self.name} (d = {dim}, budget {budget}): {self.n_init} Sobol designs, then {what}"


def choose_plan(dim: int, budget: int, batch: int = 1, least_squares: bool = False) -> Plan:
    """The plan for ``dim`` variables and ``budget`` simulations, ``batch`` designs a step; ``least_squares``: the
    problem declares residuals."""
    n_init = min(2 * dim + 2, budget - max(1, budget // 4))
    if least_squares:
        return Plan("least-squares", n_init, 0, batch)
    n_polish = max(1, budget // 10) if budget - n_init > 2 else 0
    return Plan("global" if dim <= GLOBAL_MAX_DIM else "trust-region", n_init, n_polish, batch)
