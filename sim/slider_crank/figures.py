"""Figures of slider-crank designs: the mechanism at its limit positions, an animated revolution, an effort curve.

Headless matplotlib (Agg); lengths in mm on equal-scaled axes.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

from mechopt.sim.slider_crank.kinematics import joint_positions  # noqa: E402
from mechopt.sim.slider_crank.limits import limit_positions  # noqa: E402


def _draw_pose(ax, design, theta, style, label=None):
    pos = joint_positions(design, theta)
    a, b = pos["A"], pos["B"]
    ax.plot([0, a[0], b[0]], [0, a[1], b[1]], style, lw=2, marker="o", ms=4, label=label)
    ax.add_patch(plt.Rectangle((b[0] - 0.06 * design[1], b[1] - 0.03 * design[1]), 0.12 * design[1],
                               0.06 * design[1], fill=False, ec=style[:2], lw=1.2))


def _frame_limits(designs: Mapping[str, np.ndarray]) -> tuple[tuple[float, float], tuple[float, float]]:
    xs, ys = [0.0], [0.0]
    for r, l, h in designs.values():
        xs += [-r, np.sqrt(max((l + r) ** 2 - h**2, 0.0)) + 0.1 * l]
        ys += [-r, r, h + 0.05 * l]
    pad = 0.08 * (max(xs) - min(xs))
    return (min(xs) - pad, max(xs) + pad), (min(ys) - pad, max(ys) + pad)


def limit_positions_figure(designs: Mapping[str, np.ndarray], path: Path) -> Path:
    """One panel per design: crank and rod at the extended (solid) and folded (dashed) dead centres.

    Parameters
    ----------
    designs : mapping of str to (3,) array
        Name -> (r, l, h) in mm, with r + |h| < l.
    path : Path
        PNG file to write.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    n = len(designs)
    xlim, ylim = _frame_limits(designs)
    fig, axes = plt.subplots(n, 1, figsize=(9, 1.2 + 2.6 * n * (ylim[1] - ylim[0]) / (xlim[1] - xlim[0]) * 2.2),
                             squeeze=False, sharex=True)
    for ax, (name, d) in zip(axes[:, 0], designs.items(), strict=True):
        r, l, h = d
        lim = limit_positions(r, l, h)
        ax.axhline(h, color="0.6", lw=0.8, ls=":")
        ax.add_patch(plt.Circle((0, 0), r, fill=False, color="0.7", lw=0.8))
        _draw_pose(ax, d, float(lim["theta_extended"]), "C0-", "extended dead centre")
        _draw_pose(ax, d, float(lim["theta_folded"]), "C3--", "folded dead centre")
        xe, xf = float(lim["x_extended"]), float(lim["x_folded"])
        ax.annotate("", (xe, h + 0.035 * l), (xf, h + 0.035 * l), arrowprops={"arrowstyle": "<->", "color": "k"})
        ax.text(0.5 * (xe + xf), h + 0.045 * l, f"stroke {xe - xf:.1f} mm", ha="center", va="bottom", fontsize=8)
        ax.plot(0, 0, "k^", ms=8)
        ax.set_title(f"{name}: r = {r:.2f} mm, l = {l:.2f} mm, h = {h:.2f} mm", fontsize=9)
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_aspect("equal")
        ax.set_ylabel("y (mm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    axes[-1, 0].set_xlabel("x (mm)")
    fig.suptitle("Slider-crank at its limit positions (O at the origin, slider line dotted)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def cycle_animation(design: np.ndarray, path: Path, n_frames: int = 24, title: str = "") -> Path:
    """Animated GIF of one crank revolution of a design (r, l, h) in mm, the slider's trace below."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    r, l, h = (float(v) for v in design)
    theta = np.linspace(0.0, 2 * np.pi, n_frames, endpoint=False)
    pos = joint_positions(design, theta)
    xlim, ylim = _frame_limits({"d": np.asarray(design, dtype=float)})
    fig, ax = plt.subplots(figsize=(7, 7 * (ylim[1] - ylim[0]) / (xlim[1] - xlim[0]) + 1.0), dpi=70)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.axhline(h, color="0.6", lw=0.8, ls=":")
    ax.add_patch(plt.Circle((0, 0), r, fill=False, color="0.7", lw=0.8))
    ax.plot(0, 0, "k^", ms=8)
    (links,) = ax.plot([], [], "C0-o", lw=2, ms=4)
    ax.set_title(f"{title}: r = {r:.1f}, l = {l:.1f}, h = {h:.1f} mm".lstrip(": "), fontsize=9)

    # Frames drawn on the canvas and written by Pillow directly: matplotlib's animation writer was ~20x slower.
    frames = []
    for k in range(n_frames):
        a, b = pos["A"][k], pos["B"][k]
        links.set_data([0, a[0], b[0]], [0, a[1], b[1]])
        fig.canvas.draw()
        frames.append(Image.fromarray(np.asarray(fig.canvas.buffer_rgba())[..., :3]).convert("P", palette=1))
    plt.close(fig)
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=80, loop=0)
    return path


def effort_figure(theta: np.ndarray, curves: Mapping[str, np.ndarray], desired: np.ndarray, path: Path,
                  title: str = "Spring effort over a crank revolution") -> Path:
    """Effort F(θ) (N) of named designs against the desired effort F_d, over the crank angle in degrees."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    deg = np.degrees(theta)
    ax.plot(deg, desired, "ko", ms=4, mfc="none", label="desired F_d")
    for i, (name, f) in enumerate(curves.items()):
        ax.plot(deg, f, f"C{i}-", lw=1.5, label=name)
    ax.set_xlabel("crank angle θ (deg)")
    ax.set_ylabel("effort F (N)")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
