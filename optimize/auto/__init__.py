"""The default method of :func:`mechopt.minimize` (``method="auto"``): Gaussian-process steps on a plan chosen by
the number of variables and the budget, failed simulations learned as a hidden constraint."""

from mechopt.optimize.auto.plan import Plan, choose_plan, min_budget
from mechopt.optimize.auto.search import AutoResult, auto_search

__all__ = ["AutoResult", "Plan", "auto_search", "choose_plan", "min_budget"]
