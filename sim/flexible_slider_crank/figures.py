"""Figures of the flexible slider-crank study: response curves against the target, and the rod animated."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

from mechopt.sim.flexible_slider_crank import MM, FlexibleSliderCrank, Response  # noqa: E402
from mechopt.sim.flexible_slider_crank.kinematics import rigid_motion  # noqa: E402

__all__ = ["animate_rod", "plot_responses"]


def plot_responses(r: Response, target: Response, label: str, description: str, path: Path) -> Path:
    """Three stacked panels V(t), A(t), D(t) of a design against the target; writes ``path`` (PNG)."""
    fig, axes = plt.subplots(3, 1, figsize=(8, 8.5), sharex=True)
    rows = ((r.V, target.V, 1.0, "slider velocity V (m/s)"),
            (r.A, target.A, 1.0, "slider acceleration A (m/s²)"),
            (r.D / MM, target.D / MM, 1.0, "rod mid-point deflection D (mm)"))
    for ax, (y, y_ref, _, ylabel) in zip(axes, rows, strict=True):
        ax.plot(target.t, y_ref, color="0.3", lw=2.5, alpha=0.5, label="target")
        ax.plot(r.t, y, color="C0", lw=1.2, marker=".", ms=3, label=label)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right")
    axes[-1].set_xlabel("time t (s)")
    fig.suptitle(f"Flexible slider-crank ({r.engine} engine): {label}\n{description}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def animate_rod(r: Response, p: FlexibleSliderCrank, label: str, path: Path, exaggeration: float = 20.0) -> Path:
    """Animated GIF of the mechanism over the last crank turn, the rod's deflection exaggerated, and w(s).

    Parameters
    ----------
    r : Response
        The simulated design.
    p : FlexibleSliderCrank
        Its parameters (SI).
    label : str
        Name of the design (title).
    path : Path
        GIF to write.
    exaggeration : float
        Scale of the deflection in the mechanism drawing.
    """
    period = 2.0 * np.pi / p.omega
    frames = np.nonzero(r.t >= r.t[-1] - period - 1e-12)[0][::2]
    motion = rigid_motion(p.l2, p.l3, p.omega, r.t)
    fig, (ax_m, ax_w) = plt.subplots(1, 2, figsize=(10, 3.8), dpi=80, gridspec_kw={"width_ratios": [1.6, 1]})
    ax_m.set_aspect("equal")
    span = p.l2 + p.l3
    ax_m.set_xlim(-1.2 * p.l2 / MM, 1.05 * span / MM)
    ax_m.set_ylim(-1.6 * p.l2 / MM, 1.6 * p.l2 / MM)
    ax_m.set_xlabel("x (mm)")
    ax_m.set_ylabel("y (mm)")
    ax_m.axhline(0.0, color="0.8", lw=0.8)
    (crank,) = ax_m.plot([], [], color="k", lw=3)
    (rod,) = ax_m.plot([], [], color="C0", lw=2)
    (slider,) = ax_m.plot([], [], "s", color="C3", ms=10)
    w_max = max(float(np.max(np.abs(r.shape))), 1e-12) / MM
    ax_w.set_xlim(0.0, p.l3 / MM)
    ax_w.set_ylim(-1.15 * w_max, 1.15 * w_max)
    ax_w.set_xlabel("arc length s from A (mm)")
    ax_w.set_ylabel("deflection from chord w (mm)")
    ax_w.grid(alpha=0.3)
    (curve,) = ax_w.plot([], [], color="C0", lw=2)
    title = fig.suptitle("")

    def draw(k: int):
        th, phi = motion.theta[k], motion.phi[k]
        a = np.array([np.cos(th), np.sin(th)]) * p.l2
        e = np.array([np.cos(phi), np.sin(phi)])
        n = np.array([-np.sin(phi), np.cos(phi)])
        pts = a[None, :] + np.outer(r.s, e) + exaggeration * np.outer(r.shape[k], n)
        crank.set_data([0.0, a[0] / MM], [0.0, a[1] / MM])
        rod.set_data(pts[:, 0] / MM, pts[:, 1] / MM)
        slider.set_data([motion.x[k] / MM], [0.0])
        curve.set_data(r.s / MM, r.shape[k] / MM)
        title.set_text(f"{label} ({r.engine}): t = {r.t[k]:.3f} s, crank {np.degrees(th) % 360:5.1f}°, "
                       f"deflection drawn ×{exaggeration:g}")
        return crank, rod, slider, curve, title

    fig.tight_layout(rect=(0, 0, 1, 0.93))
    images = []
    for k in frames:
        draw(int(k))
        fig.canvas.draw()
        images.append(Image.fromarray(np.asarray(fig.canvas.buffer_rgba())[..., :3]).quantize(colors=64))
    plt.close(fig)
    images[0].save(path, save_all=True, append_images=images[1:], duration=160, loop=0)
    return path
