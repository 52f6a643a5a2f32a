"""One entry point for both engines of the flexible four-bar."""

from __future__ import annotations

from mechopt.errors import InputError
from mechopt.sim.flexible_four_bar.parameters import FlexibleFourBar
from mechopt.sim.flexible_four_bar.response import FourBarResponse

__all__ = ["ENGINES", "simulate"]

#: Engine names: the paper's linear modal KED model (fast, default) and Exudyn's geometrically exact ANCF cables.
ENGINES = ("modal", "exudyn")


def simulate(p: FlexibleFourBar, engine: str = "modal") -> FourBarResponse:
    """Simulate one design.

    Parameters
    ----------
    p : FlexibleFourBar
        The design and settings (SI).
    engine : str
        ``"modal"`` or ``"exudyn"``.

    Returns
    -------
    FourBarResponse

    Raises
    ------
    InfeasibleDesignError
        When the design is not a crank-rocker.
    """
    if engine == "modal":
        from mechopt.sim.flexible_four_bar.modal import simulate_modal

        return simulate_modal(p)
    if engine == "exudyn":
        from mechopt.sim.flexible_four_bar.exudyn_engine import simulate_exudyn

        return simulate_exudyn(p)
    raise InputError(f"engine = {engine!r}; expected one of {', '.join(ENGINES)}")
