"""The live page's Plotly figures of one study snapshot: best so far, parallel coordinates, failures, the front.

Each function returns a :class:`plotly.graph_objects.Figure`; the server sends them as JSON and the page draws
them with the plotly.js that ships inside the ``plotly`` package (nothing is fetched from the internet).
"""

from __future__ import annotations

import numpy as np
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from mechopt.report.dashboard.snapshot import StudySnapshot, non_dominated

__all__ = ["failures_figure", "front_figure", "parallel_figure", "progress_figure"]

_OK, _FAILED, _INFEASIBLE = "#9aa5b1", "#d62728", "#ff7f0e"
_MARGIN = {"l": 60, "r": 20, "t": 50, "b": 45}


def _label(snap: StudySnapshot, name: str) -> str:
    unit = snap.summary.get("units", {}).get(name, "")
    return f"{name} ({unit})" if unit else name


def _var_label(var: dict) -> str:
    return f"{var['name']} ({var['unit']})" if var.get("unit") else var["name"]


def _empty(title: str, note: str) -> go.Figure:
    fig = go.Figure()
    fig.update_layout(title=title, margin=_MARGIN, xaxis={"visible": False}, yaxis={"visible": False},
                      annotations=[{"text": note, "showarrow": False, "font": {"size": 14}}])
    return fig


def progress_figure(snap: StudySnapshot) -> go.Figure:
    """Each simulation's objective and the best so far against the number of simulations (one panel an objective).

    Failed and infeasible simulations are marked on the best-so-far line, where they happened.
    """
    n = len(snap.status)
    if n == 0:
        return _empty("Best so far", "no simulation in the store yet")
    x = np.arange(1, n + 1)
    bad = np.array([s != "ok" for s in snap.status])
    fig = make_subplots(rows=len(snap.objectives), cols=1, shared_xaxes=True, vertical_spacing=0.08)
    for row, name in enumerate(snap.objectives, start=1):
        f = snap.values[name]
        best = np.fmin.accumulate(np.where(np.isfinite(f), f, np.nan))
        fig.add_trace(go.Scattergl(x=x, y=f, mode="markers", name=f"{name} of each simulation",
                                   marker={"color": _OK, "size": 5}, showlegend=row == 1), row=row, col=1)
        fig.add_trace(go.Scatter(x=x, y=best, mode="lines", name="best so far", line={"color": "#1f77b4", "width": 3},
                                 line_shape="hv", showlegend=row == 1), row=row, col=1)
        if bad.any():
            fig.add_trace(go.Scatter(x=x[bad], y=best[bad], mode="markers", name="failed or infeasible",
                                     marker={"color": _FAILED, "symbol": "x", "size": 9}, showlegend=row == 1),
                          row=row, col=1)
        fig.update_yaxes(title_text=_label(snap, name), row=row, col=1)
    fig.update_xaxes(title_text="simulations (in the order they were stored)", row=len(snap.objectives), col=1)
    fig.update_layout(title="Best so far against simulations", margin=_MARGIN, legend={"orientation": "h", "y": -0.2})
    return fig


def parallel_figure(snap: StudySnapshot) -> go.Figure:
    """Every successful design in parallel coordinates: the variables, then the objectives; coloured by the first."""
    ok = snap.ok
    title = f"Designs in parallel coordinates, coloured by {snap.objectives[0]}"
    if not ok.any():
        return _empty(title, "no successful simulation yet")
    dims = []
    for j, var in enumerate(snap.variables):
        values = snap.designs[ok, j]
        dim = {"label": _var_label(var), "values": values}
        if "lower" in var and "upper" in var:
            # The box, widened to designs sampled outside it (lines run past the bounds to fit the edges).
            dim["range"] = [min(var["lower"], values.min()), max(var["upper"], values.max())]
        dims.append(dim)
    dims += [{"label": _label(snap, k), "values": snap.values[k][ok]} for k in snap.objectives]
    color = snap.values[snap.objectives[0]][ok]
    line = {"color": color, "colorscale": "Viridis", "reversescale": True, "showscale": True,
            "colorbar": {"title": {"text": snap.objectives[0]}}}
    fig = go.Figure(go.Parcoords(line=line, dimensions=dims))
    fig.update_layout(title=title, margin={**_MARGIN, "t": 90})
    return fig


def failures_figure(snap: StudySnapshot) -> go.Figure:
    """Where the failed and infeasible designs lie among the others: every pair of variables."""
    title = "Where the failures lie (every pair of design variables)"
    if not snap.status:
        return _empty(title, "no simulation in the store yet")
    def dims_of(mask: np.ndarray) -> list[dict]:
        return [{"label": _var_label(v), "values": snap.designs[mask, j]} for j, v in enumerate(snap.variables)]

    status = np.array(snap.status)
    fig = go.Figure()
    for name, color, symbol in (("ok", _OK, "circle"), ("infeasible", _INFEASIBLE, "diamond"),
                                ("failed", _FAILED, "x")):
        mask = status == name
        if mask.any() or name == "ok":
            fig.add_trace(go.Splom(dimensions=dims_of(mask), name=f"{name} ({int(mask.sum())})", diagonal_visible=False,
                                   showupperhalf=False, marker={"color": color, "symbol": symbol, "size": 6}))
    fig.update_layout(title=title, margin=_MARGIN, legend={"orientation": "h", "y": 1.08})
    return fig


def front_figure(snap: StudySnapshot) -> go.Figure | None:
    """The non-dominated designs among the successful ones when the study has several objectives (else None)."""
    if len(snap.objectives) < 2:
        return None
    title = "The front: non-dominated designs (every objective minimised)"
    ok = snap.ok & np.all([np.isfinite(snap.values[k]) for k in snap.objectives], axis=0)
    if not ok.any():
        return _empty(title, "no successful simulation yet")
    F = np.column_stack([snap.values[k][ok] for k in snap.objectives])
    front = non_dominated(F)
    labels = [_label(snap, k) for k in snap.objectives]
    fig = go.Figure()
    if len(snap.objectives) == 2:
        order = np.argsort(F[front, 0])
        fig.add_trace(go.Scatter(x=F[~front, 0], y=F[~front, 1], mode="markers", name="dominated",
                                 marker={"color": _OK, "size": 6}))
        fig.add_trace(go.Scatter(x=F[front, 0][order], y=F[front, 1][order], mode="lines+markers",
                                 line_shape="hv", name=f"front ({int(front.sum())})",
                                 marker={"color": "#1f77b4", "size": 9}))
        fig.update_xaxes(title_text=labels[0])
        fig.update_yaxes(title_text=labels[1])
    else:
        for mask, name, color in ((~front, "dominated", _OK), (front, f"front ({int(front.sum())})", "#1f77b4")):
            fig.add_trace(go.Splom(dimensions=[{"label": lab, "values": F[mask, j]} for j, lab in enumerate(labels)],
                                   name=name, diagonal_visible=False, marker={"color": color, "size": 6}))
    fig.update_layout(title=title, margin=_MARGIN)
    return fig
