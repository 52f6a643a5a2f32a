"""Least-squares problems: Gauss-Newton steps on a problem's residual vector (the local phase of every method when
the problem declares ``residuals``) and multi-level single linkage to choose where they start."""

from mechopt.optimize.least_squares.gauss_newton import LocalRun, ResidualEvaluator, gauss_newton
from mechopt.optimize.least_squares.multistart import choose_starts, critical_distance
from mechopt.optimize.least_squares.polish import least_squares_polish

__all__ = ["LocalRun", "ResidualEvaluator", "choose_starts", "critical_distance", "gauss_newton",
           "least_squares_polish"]
