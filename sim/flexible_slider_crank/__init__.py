"""The flexible slider-crank of paper 004 (Ben Abdallah et al. 2023): an elastic connecting rod driven by the crank.

Two engines compute the slider velocity V(t), acceleration A(t) and the rod's mid-point deflection D(t):
:mod:`.modal` (the paper's linear kineto-elasto-dynamic model, numba; the fast default) and :mod:`.exudyn_engine`
(Exudyn ANCF cable elements, geometrically exact; the check).  :mod:`.parameters` holds a design and its settings,
:mod:`.kinematics` the closed-form rigid motion, :mod:`.beam` the beam elements, :mod:`.response` the result and
the paper's normalised error (Eq. 18).
"""

from mechopt.sim.flexible_slider_crank.parameters import MM, FlexibleSliderCrank
from mechopt.sim.flexible_slider_crank.response import Response, normalised_error
from mechopt.sim.flexible_slider_crank.simulate import ENGINES, simulate

__all__ = ["ENGINES", "MM", "FlexibleSliderCrank", "Response", "normalised_error", "simulate"]
