"""Figures of path-synthesis slider-cranks (matplotlib, headless): desired points, coupler curves, linkages, a GIF.

Each design is drawn on its better branch: the desired points, its coupler curve over a full crank revolution, the
segment from each desired point to its closest curve point, the linkage (crank, rod, coupler triangle, slider on its
line) at a few crank angles, and a note of the bounds and constraints active at it.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

from mechopt.sim.figure_file import figure_path, save_figure  # noqa: E402
from mechopt.sim.path_synthesis.coupler import coupler_point, linkage_joints  # noqa: E402
from mechopt.sim.path_synthesis.path_error import PathFit  # noqa: E402

__all__ = ["animate_design", "draw_linkage", "plot_designs"]


def draw_linkage(ax, design: np.ndarray, phi: float, branch: int, color: str = "C0", alpha: float = 1.0) -> list:
    """Draw the linkage at crank angle φ: ground pivot, crank O'A, rod AB, coupler triangle A-P-B, slider at B.

    Returns
    -------
    list
        The matplotlib artists drawn (for an animation to update or remove).
    """
    j = linkage_joints(design, phi, branch)
    o, a, b, p = j["O"], j["A"], j["B"], j["P"]
    size = 0.06 * float(design[1])
    arts = [*ax.plot([o[0], a[0]], [o[1], a[1]], "-", color=color, lw=2.2, alpha=alpha),
            *ax.plot([a[0], b[0]], [a[1], b[1]], "-", color=color, lw=1.6, alpha=alpha),
            ax.fill([a[0], p[0], b[0]], [a[1], p[1], b[1]], color=color, alpha=0.15 * alpha)[0],
            *ax.plot([a[0], p[0], b[0]], [a[1], p[1], b[1]], ":", color=color, lw=1.0, alpha=alpha),
            *ax.plot([o[0]], [o[1]], "k^", ms=7, alpha=alpha),
            *ax.plot([a[0], b[0], p[0]], [a[1], b[1], p[1]], "o", color=color, ms=3.5, alpha=alpha)]
    angle = np.degrees(float(design[5]))
    arts.append(ax.add_patch(plt.Rectangle((b[0] - size, b[1] - 0.5 * size), 2 * size, size, angle=angle,
                                           rotation_point="center", fill=False, ec=color, lw=1.2, alpha=alpha)))
    return arts


def _envelope(points: np.ndarray, design: np.ndarray, branch: int) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners of everything a revolution of the linkage and the points occupy."""
    j = linkage_joints(design, np.linspace(0.0, 2.0 * np.pi, 181), branch)
    every = np.concatenate([j[k] for k in ("O", "A", "B", "P")] + [points])
    lo, hi = every.min(axis=0), every.max(axis=0)
    pad = 0.08 * float(np.max(hi - lo)) + 0.06 * float(design[1])
    return lo - pad, hi + pad


def _slider_line(ax, design: np.ndarray, branch: int) -> None:
    """The slider line over the slider's travel (dashed)."""
    b = linkage_joints(design, np.linspace(0.0, 2.0 * np.pi, 181), branch)["B"]
    ends = b[[int(np.argmin(b[:, 0] + 1e-9 * b[:, 1])), int(np.argmax(b[:, 0] + 1e-9 * b[:, 1]))]]
    if np.linalg.norm(ends[1] - ends[0]) < 1e-12:
        ends = b[[int(np.argmin(b[:, 1])), int(np.argmax(b[:, 1]))]]
    t = ends[1] - ends[0]
    t = t / max(float(np.linalg.norm(t)), 1e-300) * 0.12 * float(design[1])
    ax.plot([ends[0, 0] - t[0], ends[1, 0] + t[0]], [ends[0, 1] - t[1], ends[1, 1] + t[1]], color="0.6", lw=0.9,
            ls="--", label="slider line")


def _linkage_panel(ax, points: np.ndarray, label: str, design: np.ndarray, fit: PathFit) -> None:
    phi = np.linspace(0.0, 2.0 * np.pi, 721)
    x, y = coupler_point(design, phi, fit.branch)
    _slider_line(ax, design, fit.branch)
    ax.plot(x, y, "C0-", lw=1.3, label=f"coupler curve (K = {fit.branch:+d})")
    ax.plot(points[:, 0], points[:, 1], "o", mec="C3", mfc="none", ms=4, label="desired points")
    for k, a in enumerate(np.linspace(0.0, 2.0 * np.pi, 4, endpoint=False)):
        draw_linkage(ax, design, float(a), fit.branch, color=("C2", "C1", "C4", "C5")[k], alpha=0.6)
    lo, hi = _envelope(points, design, fit.branch)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.set_title(f"{label}: E = {fit.E:.5g}, linkage at φ = 0°, 90°, 180°, 270°", fontsize=10)
    ax.legend(fontsize=7, loc="best")


def _zoom_panel(ax, points: np.ndarray, design: np.ndarray, fit: PathFit, note: list[str]) -> None:
    """The desired points, the curve near them and each point's closest curve point (red segment)."""
    phi = np.linspace(0.0, 2.0 * np.pi, 2881)
    x, y = coupler_point(design, phi, fit.branch)
    ax.plot(x, y, "C0-", lw=1.2)
    cx, cy = coupler_point(design, fit.phi, fit.branch)
    for i in range(points.shape[0]):
        ax.plot([points[i, 0], cx[i]], [points[i, 1], cy[i]], "C3-", lw=1.0)
    ax.plot(points[:, 0], points[:, 1], "o", mec="C3", mfc="none", ms=6)
    ax.plot(cx, cy, "k.", ms=3)
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 0.12 * float(np.max(hi - lo))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.set_title("desired points and their closest curve points", fontsize=9)
    ax.set_xlabel("a = (" + ", ".join(f"{v:.4g}" for v in design) + ")\nactive bounds and constraints: "
                  + ("; ".join(note) if note else "none"), fontsize=8)


def plot_designs(points: np.ndarray, designs: Mapping[str, np.ndarray], fits: Mapping[str, PathFit],
                 notes: Mapping[str, list[str]], path: str | Path, title: str = "path synthesis") -> Path:
    """One column per design: the linkage at four crank angles with its coupler curve, then a zoom on the points.

    Parameters
    ----------
    points : (N, 2) ndarray
        Desired points.
    designs : mapping of str to (8,) ndarray
        Name -> design (a1, ..., a8).
    fits : mapping of str to PathFit
        Name -> its fit (branch, closest points).
    notes : mapping of str to list of str
        Name -> the bounds and constraints active at it.
    path : str or Path
        PNG to write.
    title : str
        Figure title (the study's name).
    """
    path = figure_path(path)
    n = len(designs)
    fig, axes = plt.subplots(2, n, figsize=(6.0 * n, 10.0), squeeze=False, gridspec_kw={"height_ratios": [1.2, 1]})
    for k, (label, design) in enumerate(designs.items()):
        _linkage_panel(axes[0, k], points, label, design, fits[label])
        _zoom_panel(axes[1, k], points, design, fits[label], notes.get(label, []))
    fig.suptitle(f"{title}: slider-crank coupler curves through the desired points", fontsize=11)
    fig.tight_layout()
    return save_figure(fig, path)


def animate_design(points: np.ndarray, design: np.ndarray, fit: PathFit, path: str | Path, label: str = "",
                   n_frames: int = 36) -> Path:
    """Animated GIF of one crank revolution: the linkage moving, its coupler curve and the desired points."""
    path = figure_path(path, (".gif",))
    phi = np.linspace(0.0, 2.0 * np.pi, 721)
    x, y = coupler_point(design, phi, fit.branch)
    frames_phi = np.linspace(0.0, 2.0 * np.pi, n_frames, endpoint=False)
    lo, hi = _envelope(points, design, fit.branch)
    fig, ax = plt.subplots(figsize=(6.5, 6.5), dpi=70)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    _slider_line(ax, design, fit.branch)
    ax.plot(x, y, "C0-", lw=1.0)
    ax.plot(points[:, 0], points[:, 1], "o", mec="C3", mfc="none", ms=5)
    ax.set_title(f"{label} (K = {fit.branch:+d}): E = {fit.E:.5g}".lstrip(" "), fontsize=10)
    # Frames drawn on the canvas and written by Pillow directly (as the slider-crank's animation).
    frames = []
    for f in frames_phi:
        arts = draw_linkage(ax, design, float(f), fit.branch)
        fig.canvas.draw()
        frames.append(Image.fromarray(np.asarray(fig.canvas.buffer_rgba())[..., :3]).convert("P", palette=1))
        for art in arts:
            art.remove()
    plt.close(fig)
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=90, loop=0)
    return path
