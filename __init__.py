"""mechopt: globally optimal mechanism dimensions from a few hundred motion simulations.

The method is that of Ben Yahya et al. (2023, paper 002): simulate designs, bound the design space by feasibility,
sample the objective on parallel lines, fit each line with a sum of exponentials, blend the line models by Chebyshev
interpolation, search the blend exhaustively and validate on held-out simulations.

Subpackages: :mod:`mechopt.sim` (the physics: one folder per mechanism), :mod:`mechopt.surrogate` (the mathematics,
independent of the physics) and :mod:`mechopt.studies` (the engine that runs a study, and the shipped studies).
"""

from ._numba_cache import use_user_cache

use_user_cache()

from .errors import InfeasibleDesignError, InputError, MechoptError, StudyError  # noqa: E402

__all__ = ["InfeasibleDesignError", "InputError", "MechoptError", "StudyError"]
