"""The budget-counted problem the baselines run on (it lives in :mod:`mechopt.studies.budget`, shared with the
sparse pipeline's refinement, which must not depend on the baselines)."""

from mechopt.studies.budget import BudgetExhausted, CountedProblem, Evaluation, run_multistart

__all__ = ["BudgetExhausted", "CountedProblem", "Evaluation", "run_multistart"]
