"""One entry point for both engines of the flexible slider-crank."""

from __future__ import annotations

from mechopt.errors import InputError
from mechopt.sim.flexible_slider_crank.parameters import FlexibleSliderCrank
from mechopt.sim.flexible_slider_crank.response import Response

__all__ = ["ENGINES", "simulate"]

#: Engine names: the paper's linear modal KED model (fast, default) and Exudyn's geometrically exact ANCF cable.
ENGINES = ("modal", "exudyn")


def simulate(p: FlexibleSliderCrank, engine: str = "modal") -> Response:
    """Simulate one design.

    Parameters
    ----------
    p : FlexibleSliderCrank
        The design and settings (SI).
    engine : str
        ``"modal"`` or ``"exudyn"``.

    Returns
    -------
    Response
    """
    if engine == "modal":
        from mechopt.sim.flexible_slider_crank.modal import simulate_modal

        return simulate_modal(p)
    if engine == "exudyn":
        from mechopt.sim.flexible_slider_crank.exudyn_engine import simulate_exudyn

        return simulate_exudyn(p)
    raise InputError(f"engine = {engine!r}; expected one of {', '.join(ENGINES)}")
