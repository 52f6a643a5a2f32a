"""Analyses of a design or a result: tolerances (Monte Carlo on the margins and a model of the objective), Sobol
sensitivity, and a robust optimum."""

from mechopt.optimize.analysis.robust import RobustOptimum, robust_optimum
from mechopt.optimize.analysis.scatter import Tolerances
from mechopt.optimize.analysis.sensitivity import Sensitivity, sensitivity, sobol
from mechopt.optimize.analysis.tolerance import ToleranceResult, tolerance

__all__ = ["RobustOptimum", "Sensitivity", "ToleranceResult", "Tolerances", "robust_optimum", "sensitivity", "sobol",
           "tolerance"]
