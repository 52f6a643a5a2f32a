"""The plan of the default method, chosen from the budget and the problem's declaration (and said in the result).

* ``global`` (any number of variables): one GP over the whole box, expected-improvement steps, then a local polish
  on the model around the incumbent for the last tenth of the budget (EGO, Jones et al. 1998).  A budget above
  ``GLOBAL_MAX_POINTS`` continues from there in trust regions around the incumbent, which grow and shrink with
  success and restart at the global model's most promising point when one collapses (TuRBO, Eriksson et al. 2019);
  the last tenth of the budget then minimises the local model's mean around the best design of any restart.  In
  the trust regions a batch of several designs a step is the minimisers of as many posterior draws (Thompson
  sampling, TuRBO's choice): the kriging believer spreads a batch to the region's corners.

  The global model starts in every dimension, 5 variables and more too: with a mean level by generalised least
  squares and the additive component, a global GP in many variables is not mostly uncertainty, and it beats trust
  regions started at the Sobol design at every budget up to 200 on nearly every landscape tried.  What the trust
  regions do better is refine a sharp minimum with hundreds of simulations, so they take over from the 300th
  design (the measurements: ``docs/guide/design-evidence.md``).

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
