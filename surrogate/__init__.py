"""Mathematics of mechopt: line plans, exponential fitting, Chebyshev blending, the sparse model, its search.

The package implements Section 4 of Ben Yahya et al. (2023, paper 002): samples on l parallel lines, a 1-D exponential
fit per line, a Chebyshev blend of the line models across the normal plane, and an exhaustive search of the blended
model.  It works on generic coordinates X in R^d (d = 3 for the four-bar; the caller maps designs to coordinates)
and does not depend on the simulation code.
"""

import importlib
from typing import Any

# Imported on first use: the search module compiles numba kernels and pulls scipy.spatial, seconds that a command
# which only names SurrogateError (every command line) should not pay.
_HOME = {
    "ChebyshevBlend": "blending", "SurrogateError": "errors", "SurrogateWarning": "errors",
    "ExponentialFit": "exponential_fit", "fit_exponential": "exponential_fit", "LineHull": "lines",
    "LinePlan": "lines", "normal_basis": "lines", "SparseExponentialModel": "model", "PlanResult": "planner",
    "coverage": "planner", "plan_lines": "planner", "HullGrid": "search", "SearchResult": "search",
    "exhaustive_search": "search", "grid_minimum": "search", "hull_grid": "search",
}


def __getattr__(name: str) -> Any:
    if name in _HOME:
        return getattr(importlib.import_module(f"mechopt.surrogate.{_HOME[name]}"), name)
    raise AttributeError(f"module 'mechopt.surrogate' has no attribute {name!r}")


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
