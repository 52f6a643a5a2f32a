"""Settings of the sparse pipeline (a study's ``[surrogate]`` section; ``mechopt.minimize(options=...)``)."""

from __future__ import annotations

from typing import Any

from mechopt.optimize.options import Option, Options
from mechopt.surrogate.planner import LAYOUTS

__all__ = ["LINE_SHARE", "MIN_HELD_OUT_POINTS", "PLAN_KEYS", "VALIDATION_SHARE", "SparseOptions"]

#: Largest share of the budget the lines of the global model may take: the rest (at least a tenth) is kept for the
#: confirmation and the refinement on the simulator, which is what makes a larger budget never worse than a smaller
#: one (lines that took 147 of 150 would leave 3 to refine, and the answer would be worse than at 60).
LINE_SHARE = 0.9

#: Held-out simulations of the default validation, as a share of the budget, on top of it.
VALIDATION_SHARE = 0.2

#: Fewest points of a held-out line: fewer say little about the model between its ends.
MIN_HELD_OUT_POINTS = 6

#: The options that size the line plan (scaled together to a budget).
PLAN_KEYS = ("n_lines", "samples_per_line", "min_samples", "max_order")


class SparseOptions(Options):
    """Declared options of the sparse pipeline; ``SparseOptions.help()`` lists them."""

    DECLARED = (
        Option("plan", "auto", str, "line plan: 'auto' (the planner) or 'paper' (paper_direction and paper_origin)",
               values=("auto", "paper")),
        Option("layout", "fekete", str, "line nodes: approximate Fekete points, or on the region's outline",
               values=LAYOUTS),
        Option("fit", None, str, "what the lines' exponential sums model: the objective or its square (default: the "
               "problem's choice)", values=("value", "square"), nullable=True),
        Option("n_lines", 21, int, "lines of the global model", minimum=2),
        Option("samples_per_line", 25, int, "target samples per line", minimum=4),
        Option("min_samples", 20, int, "fewest samples a line may have", minimum=4),
        Option("max_order", 5, int, "largest number of exponential terms per line", minimum=1),
        Option("search_points", 10_000_000, int, "grid points of the exhaustive search", minimum=1000),
        Option("refine", True, bool, "refine the model's candidate by a local search on the simulator"),
        Option("fd_step", None, float, "finite-difference step of that search, fraction of the region's width "
               "(default: the problem's, above its simulator's noise)", minimum=1e-8, maximum=0.1, nullable=True),
        Option("budget", 600, int, "most simulations in all: lines, confirmation and refinement", minimum=3),
        Option("rel_tol", 0.005, float, "simulation and model agree below this relative difference", minimum=0.0),
        Option("validation_lines", 10, int, "held-out validation lines (0: no validation)", minimum=0),
        Option("validation_points", 30, int, "most points per held-out line", minimum=2),
        Option("validation_budget", None, int, "held-out simulations on top of the budget (default: 20 % of the "
               "budget; at most validation_lines x validation_points)", minimum=0, nullable=True),
        Option("paper_direction", None, list, "the paper's Δ in the model's coordinates (plan = 'paper')",
               nullable=True),
        Option("paper_origin", None, list, "the paper's origin in the model's coordinates (plan = 'paper')",
               nullable=True),
        Option("paper_lines", 7, int, "lines of the paper's plan", minimum=2),
        Option("seed", 0, int, "seed of the planner and of the validation lines", minimum=0),
    )

    @staticmethod
    def scaled_plan(budget: int, dim: int = 3) -> dict[str, Any]:
        """The line plan's options (:data:`PLAN_KEYS`) for a simulation budget; empty from 600 on (the defaults).

        Below 600 simulations a blend accurate to 1 % is out of reach.  Below 200, the first plan is the smallest
        that gives a blend (3 lines of 4 samples, the fewest an order-1 exponential fit checks; 5 in 2-D, where a
        thin region leaves a short line fewer feasible samples), and every other simulation goes to the model's
        trust-region steps and the local search, which recover the basin's bottom faster than more lines would
        (measured on the ventilator: +0.3 % from 12 simulations, against +40 % with the lines alone).  From 200, 7
        lines on 60 % of the budget.  From 600 on: 21 lines of 25 samples (held-out error below 1 % on the
        ventilator).
        """
        if budget >= 600:
            return {}
        if budget < 200:
            n_lines, per_line = 3, (5 if dim == 2 else 4)
        else:
            n_lines, per_line = 7, int(min(max(round(0.6 * budget / 7), 8), 60))
        if dim == 4:
            # A 3-D blend needs a complete degree (4, 10 nodes...) and lines enough for the hull to have volume.
            n_lines = 5 if budget < 200 else 10
            per_line = int(min(max(round(0.8 * budget / n_lines), 5), 30))
        return {"n_lines": n_lines, "samples_per_line": per_line, "min_samples": max(4, int(0.6 * per_line)),
                "max_order": max(1, min(5, per_line // 2 - 1)) if per_line < 12 else 5}

    @classmethod
    def for_budget(cls, budget: int, dim: int = 3, seed: int = 0, **given: Any) -> SparseOptions:
        """The pipeline scaled to a simulation budget (:meth:`scaled_plan`); explicit ``given`` options win."""
        scaled = cls.scaled_plan(int(budget), dim)
        return cls({"search_points": 2_000_000, **scaled, "budget": int(budget), "seed": int(seed), **given})

    def line_cap(self) -> int:
        """Most simulations the lines of the global model may take: :data:`LINE_SHARE` of the budget, and one
        fewer than the budget (the candidate's confirmation)."""
        return max(2, min(self.budget - 1, int(LINE_SHARE * self.budget)))

    def validation_plan(self) -> tuple[int, int]:
        """Held-out lines and points per line of the validation, on top of the budget; (0, 0) for none.

        ``validation_budget`` simulations (default :data:`VALIDATION_SHARE` of the budget) spread over at most
        ``validation_lines`` lines of at least :data:`MIN_HELD_OUT_POINTS` (or ``validation_points`` when fewer) and
        at most ``validation_points`` points: more directions first, then more points along each.
        """
        total = self.validation_budget
        if total is None:
            total = int(VALIDATION_SHARE * self.budget)
        total = min(total, self.validation_lines * self.validation_points)
        if self.validation_lines <= 0:
            return 0, 0
        # A user who asks for shorter held-out lines (--points-per-line) gets more of them for the same cost.
        shortest = min(MIN_HELD_OUT_POINTS, self.validation_points)
        if total < shortest:
            return 0, 0
        lines = min(self.validation_lines, total // shortest)
        return lines, min(self.validation_points, total // lines)
