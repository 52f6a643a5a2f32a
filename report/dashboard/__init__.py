"""The live page of a run: ``mechopt dashboard PATH`` reads a sample store (or a study's output folder) and shows
its studies while they run and after they end, refreshed by itself.

The server (:mod:`.server`) reads the store read-only, never the running optimizer; the figures (:mod:`.figures`)
are Plotly's, drawn in the browser by the plotly.js inside the installed ``plotly`` package.
"""

from __future__ import annotations

__all__ = ["DashboardServer"]


def __getattr__(name: str):
    # plotly (the ``dashboard`` extra) is imported only when the page is served.
    if name == "DashboardServer":
        from mechopt.report.dashboard.server import DashboardServer

        return DashboardServer
    raise AttributeError(name)
