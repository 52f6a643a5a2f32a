"""Figures of a study run, for any problem (matplotlib, headless): the feasible region with each constraint's
boundary, the sampling lines and their hull, and the model against held-out simulations."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from mechopt.optimize.problem import DesignProblem  # noqa: E402
from mechopt.sim.figure_file import figure_path, save_figure  # noqa: E402

__all__ = ["plot_feasible_3d", "plot_feasible_slices", "plot_validation"]


def _slice_tolerance(problem: DesignProblem) -> float:
    """Two values of the first variable closer than this are one slice (a millionth of its range)."""
    lo, hi = problem.bounds[0]
    return 1e-6 * float(hi - lo)


def _slice_values(problem: DesignProblem, marks: Mapping[str, np.ndarray], n_slices: int) -> list[float]:
    lo, hi = problem.bounds[0]
    tol = _slice_tolerance(problem)
    # A mark's own value first: an optimum on a bound (|OA| = 30 mm, computed as 30.0000000003) is that bound's
    # slice, not a second one beside it.
    values: list[float] = []
    for v in [*(float(m[0]) for m in marks.values() if lo - tol <= m[0] <= hi + tol),
              float(lo), float(hi), float(0.5 * (lo + hi))]:
        if all(abs(v - w) > tol for w in values):
            values.append(min(max(v, float(lo)), float(hi)))
    n_marked = sum(1 for v in values if any(abs(v - float(m[0])) <= tol for m in marks.values()))
    return sorted(values[:max(n_slices, n_marked)])


def _draw_marks(ax, problem: DesignProblem, marks: Mapping[str, np.ndarray], value: float | None, ix: int,
                iy: int) -> None:
    """The marked designs of one slice (those whose first variable is the slice's ``value``), labelled."""
    b = problem.bounds
    for j, (name, m) in enumerate(marks.items()):
        if value is not None and abs(float(m[0]) - value) > _slice_tolerance(problem):
            continue
        marker = "*" if "optimum" in name else "o"
        ax.plot(m[ix], m[iy], marker, color="k", ms=12 if marker == "*" else 7, zorder=5)
        # Labels alternate above and below their marker, so that close designs do not overwrite each other;
        # near the bottom or top edge (an optimum on a bound) the label goes inside the axes.
        dy = 8 if j % 2 == 0 else -13
        height = (m[iy] - b[iy, 0]) / (b[iy, 1] - b[iy, 0])
        dy = 8 if height < 0.1 else (-13 if height > 0.9 else dy)
        ax.annotate(name, (m[ix], m[iy]), textcoords="offset points", xytext=(7, dy),
                    fontsize=8, bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8})


def _constraint_plane(problem: DesignProblem, base: np.ndarray) -> tuple[int, int]:
    """The two variables after the first whose change moves the constraint margins most at ``base`` (over their
    range): above 3 variables the last two may not enter any constraint (a translation of a whole linkage)."""
    d, b = problem.dim, problem.bounds
    if not problem.constraints:
        return d - 2, d - 1
    h = 1e-4 * (b[:, 1] - b[:, 0])
    X = np.vstack([base, base + np.diag(h)])
    M = np.nan_to_num(problem.constraint_margins(X), nan=0.0, posinf=0.0, neginf=0.0)
    effect = np.max(np.abs(M[1:] - M[0]), axis=1) / 1e-4
    effect[0] = -1.0  # the slices' variable
    first, second = sorted(int(i) for i in np.argsort(-effect)[:2])
    return first, second


def plot_feasible_slices(problem: DesignProblem, path: str | Path, marks: Mapping[str, np.ndarray] | None = None,
                         n_slices: int = 4, n: int = 240, model=None) -> Path:
    """The feasible region with each constraint's zero contour (paper Fig. 7, 12).

    For d = 2 one panel of the plane; for d >= 3 slices in the plane of the last two variables at fixed values of
    the first (the others at the optimum's values when a mark is named so, else at the middle of their range: in 8
    variables the middle of the box is rarely feasible), one slice at each marked design's own value, so that every
    mark is drawn where it lies.

    Parameters
    ----------
    problem : DesignProblem
        Box and constraints.
    path : str or Path
        PNG file.
    marks : mapping, optional
        Designs to mark, name -> (d,) array.
    n_slices : int
        Slices for d >= 3 (more when there are more marks).
    n : int
        Grid resolution per axis.
    model : ObjectiveModel, optional
        For d = 2, its prediction of the objective is drawn as contour lines over the feasible region.
    """
    path = figure_path(path)
    marks = dict(marks or {})
    d = problem.dim
    b = problem.bounds
    optimum = next((np.asarray(x, dtype=float) for name, x in marks.items() if "optimum" in name), None)
    base = optimum if optimum is not None and d > 3 else 0.5 * (b[:, 0] + b[:, 1])
    ix, iy = (0, 1) if d == 2 else (d - 2, d - 1) if d == 3 else _constraint_plane(problem, base)
    gx, gy = np.linspace(*b[ix], n), np.linspace(*b[iy], n)
    GX, GY = np.meshgrid(gx, gy, indexing="ij")
    slices = [None] if d == 2 else _slice_values(problem, marks, n_slices)
    width = 8.5 if d == 2 else 4.8 * len(slices) + 0.6
    fig, axes = plt.subplots(1, len(slices), figsize=(width, 6.2 if d == 2 else 4.9), squeeze=False)
    handles: dict[str, object] = {}
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    if len(problem.constraints) > len(colors):  # path synthesis has 14: one colour, one constraint
        colors = [plt.cm.tab20(i) for i in range(20)]
    for ax, value in zip(axes[0], slices, strict=True):
        X = np.tile(base, (GX.size, 1))
        if value is not None:
            X[:, 0] = value
        X[:, ix], X[:, iy] = GX.ravel(), GY.ravel()
        # The margins once: the feasible region and each constraint's contour come from the same array.
        M = problem.constraint_margins(X) if problem.constraints else None
        feasible = problem.feasible(X, margins=M).reshape(GX.shape)
        ax.contourf(GX, GY, feasible.astype(float), levels=[0.5, 1.5], colors=["#cfe8cf"])
        if model is not None and d == 2:
            Z = np.where(feasible.ravel() & model.contains(X), model.predict(X), np.nan).reshape(GX.shape)
            if np.isfinite(Z).sum() > 10:
                levels = np.nanquantile(Z, np.linspace(0.02, 0.9, 9))
                cs = ax.contour(GX, GY, Z, levels=np.unique(levels), colors="0.35", linewidths=0.7)
                ax.clabel(cs, fontsize=7, fmt="%.3g")
                handles["model"] = plt.Line2D([], [], color="0.35", lw=0.7, label=f"model {problem.objective}")
        if problem.constraints:
            for k, name in enumerate(problem.constraints):
                values = np.nan_to_num(M[:, k].reshape(GX.shape), nan=-1.0, neginf=-1.0)
                if values.min() < 0 < values.max():
                    color, style = colors[k % len(colors)], ("-", "--", ":")[k // len(colors) % 3]
                    ax.contour(GX, GY, values, levels=[0.0], colors=[color], linewidths=1.6, linestyles=style)
                    handles[name] = plt.Line2D([], [], color=color, lw=1.6, ls=style, label=f"{name} = 0")
        _draw_marks(ax, problem, marks, value, ix, iy)
        v = problem.variables
        ax.set_xlabel(v[ix].axis_label)
        ax.set_ylabel(v[iy].axis_label)
        if value is not None:
            ax.set_title(f"{v[0].label or v[0].name} = {value:.4g} {v[0].unit}".strip(), fontsize=10)
        ax.grid(alpha=0.25)
    handles["feasible"] = plt.Rectangle((0, 0), 1, 1, color="#cfe8cf", label="feasible")
    ncol = min(len(handles), 3 if d == 2 else 6)
    fig.legend(handles=list(handles.values()), fontsize=8, loc="lower center", ncol=ncol, frameon=False)
    what = "the design space" if d == 2 else f"slices at fixed {problem.variables[0].label or problem.names[0]}"
    fig.suptitle(f"Feasible designs of '{problem.name}' ({what}),\neach constraint's boundary"
                 + (" and the model's contours" if model is not None and d == 2 else ""), fontsize=11)
    rows = -(-len(handles) // ncol)
    fig.tight_layout(rect=(0, 0.03 + 0.035 * rows, 1, 1))
    return save_figure(fig, path)


def plot_feasible_3d(problem: DesignProblem, path: str | Path, lines: list[np.ndarray] | None = None,
                     hull_points: np.ndarray | None = None, marks: Mapping[str, np.ndarray] | None = None,
                     n_points: int = 6000, seed: int = 0) -> Path:
    """3-D view of a 3-variable problem's feasible region with the sampling lines and their hull (paper Fig. 15)."""
    from scipy.spatial import ConvexHull

    path = figure_path(path)
    b = problem.bounds
    rng = np.random.default_rng(seed)
    cloud = rng.uniform(b[:, 0], b[:, 1], size=(8 * n_points, 3))
    cloud = cloud[problem.feasible(cloud)][:n_points]
    fig = plt.figure(figsize=(8.5, 7))
    ax = fig.add_subplot(projection="3d")
    ax.scatter(cloud[:, 0], cloud[:, 1], cloud[:, 2], s=3, c="#2e8b57", alpha=0.18, depthshade=False,
               label="feasible designs")
    for i, pts in enumerate(lines or []):
        ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], ".-", color="C3", ms=2.5, lw=1,
                label="sampling lines" if i == 0 else None)
    if hull_points is not None and len(hull_points) >= 4:
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        hull = ConvexHull(hull_points)
        tris = [hull_points[s] for s in hull.simplices]
        ax.add_collection3d(Poly3DCollection(tris, facecolor="C0", alpha=0.08, edgecolor="C0", linewidth=0.2))
    for name, m in (marks or {}).items():
        ax.scatter([m[0]], [m[1]], [m[2]], s=80, marker="*" if "optimum" in name else "o", color="k")
        ax.text(m[0], m[1], m[2], f"  {name}", fontsize=8)
    v = problem.variables
    ax.set_xlabel(v[0].axis_label)
    ax.set_ylabel(v[1].axis_label)
    ax.set_zlabel(v[2].axis_label)
    ax.view_init(elev=22, azim=-58)
    ax.set_title(f"Feasible region of '{problem.name}', sampling lines and their convex hull", fontsize=10)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_validation(lines: list[dict], path: str | Path, fit_lines: list[tuple[np.ndarray, np.ndarray]] | None = None,
                    model=None, label: str = "objective", unit: str = "") -> Path:
    """The model against simulations along its fitting lines and held-out lines (paper Fig. 16), with the error.

    Parameters
    ----------
    lines : list of dict
        Held-out lines: ``designs``, ``simulated``, ``predicted``.
    path : str or Path
        PNG file.
    fit_lines : list of (designs, values), optional
        The fitting lines (the model interpolates them).
    model : ObjectiveModel, optional
        To draw its curve along the fitting lines.
    label : str
        The objective with its unit, for the axis.
    unit : str
        The objective's unit, for the error axis.
    """
    path = figure_path(path)
    fig, (ax, ax_err) = plt.subplots(2, 1, figsize=(11, 6.4), sharex=True, gridspec_kw={"height_ratios": [2.2, 1]})
    x0 = 0
    for i, (designs, values) in enumerate(fit_lines or []):
        x = x0 + np.arange(len(values))
        ax.plot(x, values, "o", ms=4, mfc="none", color="C3", label="fitting lines (simulated)" if i == 0 else None)
        if model is not None:
            pred = model.predict(designs)
            ax.plot(x, pred, "-", color="C0", lw=1.3, zorder=4, label="model" if i == 0 else None)
            ax_err.plot(x, pred - values, ".", ms=3, color="C3")
        x0 += len(values) + 4
    for i, line in enumerate(lines):
        sim, pred = np.asarray(line["simulated"]), np.asarray(line["predicted"])
        x = x0 + np.arange(len(sim))
        ax.plot(x, sim, "s", ms=4, mfc="none", color="C4", label="held-out lines (simulated)" if i == 0 else None)
        ax.plot(x, pred, "-", color="C0", lw=1.3, zorder=4, label=None if (fit_lines and model) else
                ("model" if i == 0 else None))
        ax_err.plot(x, pred - sim, ".", ms=3, color="C4")
        x0 += len(sim) + 4
    ax.set_ylabel(label)
    ax.set_title("Model against simulations on its fitting lines and on held-out lines", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax_err.axhline(0, color="0.5", lw=0.8)
    ax_err.set_ylabel(f"model − simulation ({unit})" if unit else "model − simulation")
    ax_err.set_xlabel("sample along the lines, one line after the other")
    ax_err.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)
