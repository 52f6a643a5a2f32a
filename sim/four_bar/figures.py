"""Figures of a four-bar (matplotlib, headless): torque over the cycle, mechanism drawings, an animated cycle."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from mechopt.sim.figure_file import figure_path, save_figure  # noqa: E402
from mechopt.sim.four_bar.kinematics import joint_positions  # noqa: E402
from mechopt.sim.four_bar.mechanism import FourBar  # noqa: E402
from mechopt.sim.four_bar.result import SimulationResult  # noqa: E402


def draw_mechanism(ax, design: np.ndarray, mechanism: FourBar, psi: float, color: str, label: str | None = None,
                   alpha: float = 1.0) -> None:
    """Draw the four-bar O-A-B-C of ``design`` (mm) at output angle ``psi`` (rad) on ``ax``."""
    mech = mechanism
    pos = joint_positions(design, mech.pivot_c, np.array([psi]), mech.branch)
    pts = np.array([pos[k][0] for k in ("O", "A", "B", "C")])
    ax.plot(pts[:, 0], pts[:, 1], "-o", color=color, lw=2.2, ms=4, alpha=alpha, label=label)


def draw_grounds(ax, mechanism: FourBar) -> None:
    """Mark the ground pivots O and C."""
    xc, yc = mechanism.pivot_c
    ax.plot([0, xc], [0, yc], "k^", ms=9, zorder=5)
    ax.annotate("O", (0, 0), textcoords="offset points", xytext=(6, -12))
    ax.annotate("C", (xc, yc), textcoords="offset points", xytext=(6, -12))


def plot_simulation(result: SimulationResult, mechanism: FourBar, path: str | Path) -> Path:
    """Torque over the cycle (left) and the mechanism at ψ_start and ψ_end (right), saved to ``path``.

    Parameters
    ----------
    result : SimulationResult
        A simulated design.
    mechanism : FourBar
        The mechanism (pivot C and the stroke).
    path : str or Path
        PNG file to write.
    """
    path = figure_path(path)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.6), gridspec_kw={"width_ratios": [1.3, 1]})
    ax1.plot(result.t, result.tau, color="C0", lw=1.8)
    ax1.axhline(0, color="0.6", lw=0.8)
    for level, style in ((result.t_rms, "--"), (-result.t_rms, "--")):
        ax1.axhline(level, color="C3", ls=style, lw=1)
    ax1.set_xlabel("time t (s)")
    ax1.set_ylabel("motor torque τ (N·m)")
    d = result.design
    ax1.set_title(f"Motor torque over one cycle ({result.engine}): T_RMS = {result.t_rms:.3f} N·m "
                  f"(dashed), T_max = {result.t_max:.3f} N·m", fontsize=10)
    ax1.grid(alpha=0.3)
    draw_grounds(ax2, mechanism)
    draw_mechanism(ax2, d, mechanism, mechanism.psi_start, "C0", "ψ_start")
    draw_mechanism(ax2, d, mechanism, mechanism.psi_end, "C1", "ψ_end")
    ax2.set_aspect("equal")
    ax2.set_xlabel("x (mm)")
    ax2.set_ylabel("y (mm)")
    ax2.set_title(f"|OA|={d[0]:.2f}, |AB|={d[1]:.2f}, |BC|={d[2]:.2f} mm", fontsize=10)
    ax2.legend(loc="best", fontsize=9)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_torque_comparison(results: dict[str, SimulationResult], path: str | Path) -> Path:
    """Motor torque over the cycle of several designs on one axis (paper Fig. 2)."""
    path = figure_path(path)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for name, r in results.items():
        ax.plot(r.t, r.tau, lw=1.8, label=f"{name}: T_RMS {r.t_rms:.2f}, T_max {r.t_max:.2f} N·m")
    ax.axhline(0, color="0.6", lw=0.8)
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("motor torque τ (N·m)")
    ax.set_title("Motor torque over one cycle, simulated with pymunk", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_mechanisms(designs: dict[str, np.ndarray], mechanism: FourBar, path: str | Path) -> Path:
    """Each design drawn at ψ_start and ψ_end, side by side, on one common scale (mm on both axes of every panel).

    Parameters
    ----------
    designs : dict
        Name -> (|OA|, |AB|, |BC|) in mm.
    mechanism : FourBar
        Pivot C and stroke.
    path : str or Path
        PNG file to write.
    """
    path = figure_path(path)
    # One set of limits for every panel, so that the designs compare at a glance.
    pts = []
    for d in designs.values():
        pos = joint_positions(d, mechanism.pivot_c, np.array([mechanism.psi_start, mechanism.psi_end]),
                              mechanism.branch)
        pts += [pos[k] for k in "OABC"]
    pts = np.vstack(pts)
    pad = 0.08 * np.ptp(pts, axis=0).max()
    lo, hi = pts.min(axis=0) - pad, pts.max(axis=0) + pad
    fig, axes = plt.subplots(1, len(designs), figsize=(5.5 * len(designs), 4.4), squeeze=False)
    for ax, (name, d) in zip(axes[0], designs.items(), strict=True):
        draw_grounds(ax, mechanism)
        draw_mechanism(ax, d, mechanism, mechanism.psi_start, "C0", "ψ_start")
        draw_mechanism(ax, d, mechanism, mechanism.psi_end, "C1", "ψ_end")
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_title(f"{name}: |OA|={d[0]:.2f}, |AB|={d[1]:.2f}, |BC|={d[2]:.2f} mm", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    return save_figure(fig, path)


def animate_cycle(result: SimulationResult, mechanism: FourBar, path: str | Path, frames: int = 40) -> Path:
    """Animated GIF of a design through its cycle, with the torque trace growing beside it."""
    path = figure_path(path, (".gif",))
    mech = mechanism
    idx = np.linspace(0, result.t.size - 1, frames).astype(int)
    pos = joint_positions(result.design, mech.pivot_c, result.psi[idx], mech.branch)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.6), gridspec_kw={"width_ratios": [1.2, 1]})
    draw_grounds(ax1, mechanism)
    allx = np.concatenate([pos[k][:, 0] for k in "OABC"])
    ally = np.concatenate([pos[k][:, 1] for k in "OABC"])
    ax1.set_xlim(allx.min() - 20, allx.max() + 20)
    ax1.set_ylim(ally.min() - 20, ally.max() + 20)
    ax1.set_aspect("equal")
    ax1.set_xlabel("x (mm)")
    ax1.set_ylabel("y (mm)")
    (link,) = ax1.plot([], [], "-o", color="C0", lw=2.5)
    ax2.plot(result.t, result.tau, color="0.8", lw=1)
    (trace,) = ax2.plot([], [], color="C3", lw=1.8)
    (dot,) = ax2.plot([], [], "o", color="C3")
    ax2.set_xlabel("time t (s)")
    ax2.set_ylabel("motor torque τ (N·m)")
    d = result.design
    fig.suptitle(f"|OA|={d[0]:.2f}, |AB|={d[1]:.2f}, |BC|={d[2]:.2f} mm through one cycle", fontsize=10)
    fig.tight_layout()

    def update(f):
        pts = np.array([pos[k][f] for k in "OABC"])
        link.set_data(pts[:, 0], pts[:, 1])
        k = idx[f]
        trace.set_data(result.t[: k + 1], result.tau[: k + 1])
        dot.set_data([result.t[k]], [result.tau[k]])
        return link, trace, dot

    # The still parts are drawn once and each frame only redraws the moving artists over them (blitting by hand):
    # matplotlib's writer redraws the whole figure per frame, which made this GIF most of a small study's time.
    from PIL import Image

    fig.canvas.draw()
    background = fig.canvas.copy_from_bbox(fig.bbox)
    images = []
    for f in range(frames):
        fig.canvas.restore_region(background)
        for artist in update(f):
            artist.axes.draw_artist(artist)
        images.append(Image.fromarray(np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()))
    palette = images[-1].quantize(colors=64)  # the last frame holds every colour; one palette keeps them steady
    frames_p = [im.quantize(palette=palette) for im in images]
    frames_p[0].save(path, save_all=True, append_images=frames_p[1:], duration=round(1000 / 12), loop=0)
    plt.close(fig)
    return path
