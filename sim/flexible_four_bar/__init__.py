"""The flexible four-bar of paper 004 (Ben Abdallah et al. 2023, Section 3.2): a rigid crank driving a flexible
coupler and a flexible follower.

Two engines compute the mid-point paths of the three moving links and the mid-span deflections of the two flexible
ones: :mod:`.modal` (the paper's linear kineto-elasto-dynamic model, numba; the fast default) and
:mod:`.exudyn_engine` (Exudyn ANCF cable elements, geometrically exact; the check).  :mod:`.parameters` holds a
design and its settings, :mod:`.kinematics` the closed-form rigid motion and the crank-rocker margins, :mod:`.loads`
the links' inertia loads and axial forces, :mod:`.response` the result and the paper's five-term error (Eq. 25),
:mod:`.problem` the design problem, :mod:`.figures` its figures.
"""

from mechopt.sim.flexible_four_bar.parameters import MM, FlexibleFourBar, FlexibleLink
from mechopt.sim.flexible_four_bar.response import FourBarResponse, five_term_error
from mechopt.sim.flexible_four_bar.simulate import ENGINES, simulate

__all__ = ["ENGINES", "MM", "FlexibleFourBar", "FlexibleLink", "FourBarResponse", "five_term_error", "simulate"]
