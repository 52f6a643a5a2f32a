"""The path-generating slider-crank of paper 000 (Hernández et al. 2021): eight dimensions, unprescribed timing.

:mod:`.coupler` holds the coupler point as a function of the crank angle on both branches (Eqs. 5-10),
:mod:`.closest_point` the closest curve point to each desired point (grid, then safeguarded Newton),
:mod:`.path_error` the error E of Eq. 11 on the better branch and its residual vector, :mod:`.jacobian` the
residuals' exact Jacobian, :mod:`.feasibility` the margins (Grashof, bar ratio), :mod:`.points` the desired points'
CSV reader, :mod:`.problem` the design problem and :mod:`.figures` its figures.
"""

from mechopt.sim.path_synthesis.coupler import BRANCHES, coupler_point, linkage_joints
from mechopt.sim.path_synthesis.feasibility import CONSTRAINTS, margins
from mechopt.sim.path_synthesis.path_error import PathFit, fit_path
from mechopt.sim.path_synthesis.points import read_points
from mechopt.sim.path_synthesis.problem import VARIABLES, PathSynthesisProblem

__all__ = ["BRANCHES", "CONSTRAINTS", "VARIABLES", "PathFit", "PathSynthesisProblem", "coupler_point", "fit_path",
           "linkage_joints", "margins", "read_points"]
