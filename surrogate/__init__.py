"""Mathematics of mechopt: line plans, exponential fitting, Chebyshev blending, the sparse model, its search.

The package implements Section 4 of Ben Yahya et al. (2023, paper 002): samples on l parallel lines, a 1-D exponential
fit per line, a Chebyshev blend of the line models across the normal plane, and an exhaustive search of the blended
model.  It works on generic coordinates X in R^d (d = 3 for the four-bar; the caller maps designs to coordinates)
and does not depend on the simulation code.
"""

from mechopt.surrogate.blending import ChebyshevBlend
from mechopt.surrogate.errors import SurrogateError, SurrogateWarning
from mechopt.surrogate.exponential_fit import ExponentialFit, fit_exponential
from mechopt.surrogate.lines import LineHull, LinePlan, normal_basis
from mechopt.surrogate.model import SparseExponentialModel
from mechopt.surrogate.planner import PlanResult, coverage, plan_lines
from mechopt.surrogate.search import HullGrid, SearchResult, exhaustive_search, grid_minimum, hull_grid

__all__ = [
    "ChebyshevBlend",
    "ExponentialFit",
    "HullGrid",
    "LineHull",
    "LinePlan",
    "PlanResult",
    "SearchResult",
    "SparseExponentialModel",
    "SurrogateError",
    "SurrogateWarning",
    "coverage",
    "exhaustive_search",
    "fit_exponential",
    "grid_minimum",
    "hull_grid",
    "normal_basis",
    "plan_lines",
]
