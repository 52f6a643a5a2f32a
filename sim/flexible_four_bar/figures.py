"""Figures of the flexible four-bar study: the five responses of Eq. 25 against the target; the mechanism animated."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

from mechopt.sim.flexible_four_bar.kinematics import rigid_motion  # noqa: E402
from mechopt.sim.flexible_four_bar.parameters import MM, FlexibleFourBar  # noqa: E402
from mechopt.sim.flexible_four_bar.response import FourBarResponse  # noqa: E402

__all__ = ["animate_mechanism", "plot_responses"]

_PATHS = (("crank", "crank mid-point path"), ("coupler", "coupler mid-point path"),
          ("follower", "follower mid-point path"))


def plot_responses(target: FourBarResponse, runs: Mapping[str, tuple[FourBarResponse, float]], path: Path) -> Path:
    """Five panels: the three mid-point paths (x, y in mm) and D3(t), D4(t) (mm) of each design and the target.

    Parameters
    ----------
    target : FourBarResponse
        The target's responses (drawn thick and grey).
    runs : mapping of str to (FourBarResponse, float)
        Each design's responses and its f (legend).
    path : Path
        PNG to write.
    """
    fig = plt.figure(figsize=(14, 9), layout="constrained")
    grid = fig.add_gridspec(2, 6)
    path_axes = [fig.add_subplot(grid[0, 2 * k: 2 * k + 2]) for k in range(3)]
    d_axes = [fig.add_subplot(grid[1, 3 * k: 3 * k + 3]) for k in range(2)]
    styles = ["-", "--", ":", "-."]
    for ax, (key, title) in zip(path_axes, _PATHS, strict=True):
        P = getattr(target, key) / MM
        ax.plot(P[:, 0], P[:, 1], color="0.3", lw=3, alpha=0.45, label="target")
        for i, (r, _) in enumerate(runs.values()):
            Q = getattr(r, key) / MM
            ax.plot(Q[:, 0], Q[:, 1], ls=styles[i % 4], color=f"C{i}", lw=1.3)
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_aspect("equal", adjustable="box")
        ax.grid(alpha=0.3)
    for ax, key, title in zip(d_axes, ("D3", "D4"), ("coupler mid-span deflection D3", "follower mid-span "
                                                                                      "deflection D4"), strict=True):
        ax.plot(target.t, getattr(target, key) / MM, color="0.3", lw=3, alpha=0.45, label="target")
        for i, (label, (r, _)) in enumerate(runs.items()):
            ax.plot(r.t, getattr(r, key) / MM, ls=styles[i % 4], color=f"C{i}", lw=1.3, marker=".", ms=2.5,
                    label=label)
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("time t (s)")
        ax.set_ylabel("deflection from chord (mm)")
        ax.grid(alpha=0.3)
    handles, labels = d_axes[0].get_legend_handles_labels()
    labels = ["target", *(f"{label} (f = {f:.3g})" for label, (_, f) in runs.items())]
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(runs) + 1, 4), fontsize=9)
    fig.suptitle(f"Flexible four-bar ({target.engine} engine): the five responses of Eq. 25 against the target",
                 fontsize=11)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def _frame_points(r: FourBarResponse, p: FlexibleFourBar, motion, k: int, exaggeration: float):
    """Crank, coupler and follower polylines (mm) of frame ``k``, the deflections magnified."""
    b, c = motion.B[k], motion.C[k]
    o4 = np.array([p.l1, 0.0])
    out = [np.stack([np.zeros(2), b])]
    for start, end, s, shape in ((b, c, r.s3, r.shape3[k]), (o4, c, r.s4, r.shape4[k])):
        e = (end - start) / np.linalg.norm(end - start)
        n = np.array([-e[1], e[0]])
        out.append(start + np.outer(s, e) + exaggeration * np.outer(shape, n))
    return [q / MM for q in out]


def animate_mechanism(r: FourBarResponse, p: FlexibleFourBar, label: str, path: Path,
                      exaggeration: float = 20.0) -> Path:
    """Animated GIF of the four-bar over its last crank turn, the links' deflections magnified, and the paths.

    Parameters
    ----------
    r : FourBarResponse
        The simulated design.
    p : FlexibleFourBar
        Its parameters (SI).
    label : str
        Name of the design (title).
    path : Path
        GIF to write.
    exaggeration : float
        Scale of the deflections in the drawing.
    """
    period = 2.0 * np.pi / p.omega
    frames = np.nonzero(r.t >= r.t[-1] - period - 1e-12)[0][::2]
    motion = rigid_motion(p.lengths, p.omega, r.t, p.branch)
    fig, ax = plt.subplots(figsize=(7.5, 5.6), dpi=80)
    ax.set_aspect("equal")
    pts = np.concatenate([motion.B, motion.C, [[0.0, 0.0], [p.l1, 0.0]]]) / MM
    pad = 0.12 * np.ptp(pts, axis=0).max()
    ax.set_xlim(pts[:, 0].min() - pad, pts[:, 0].max() + pad)
    ax.set_ylim(pts[:, 1].min() - pad, pts[:, 1].max() + pad)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.grid(alpha=0.3)
    ax.plot([0.0, p.l1 / MM], [0.0, 0.0], "^", color="k", ms=10)
    for key, color in (("crank", "k"), ("coupler", "C0"), ("follower", "C3")):
        P = getattr(r, key) / MM
        ax.plot(P[:, 0], P[:, 1], color=color, lw=0.8, alpha=0.4)
    lines = [ax.plot([], [], color=c, lw=w, marker="o", ms=3, markevery=[0, -1])[0]
             for c, w in (("k", 4), ("C0", 2), ("C3", 2))]
    title = ax.set_title("", fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    images = []
    for k in frames:
        for line, q in zip(lines, _frame_points(r, p, motion, int(k), exaggeration), strict=True):
            line.set_data(q[:, 0], q[:, 1])
        title.set_text(f"{label} ({r.engine}): t = {r.t[k]:.3f} s, crank {np.degrees(motion.theta2[k]) % 360:5.1f}°,"
                       f" deflections ×{exaggeration:g}")
        fig.canvas.draw()
        images.append(Image.fromarray(np.asarray(fig.canvas.buffer_rgba())[..., :3]).quantize(colors=64))
    plt.close(fig)
    images[0].save(path, save_all=True, append_images=images[1:], duration=160, loop=0)
    return path
