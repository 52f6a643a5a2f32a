"""Figures of mechopt (matplotlib, headless): torque curves, mechanism drawings, feasible regions, validation."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from sim.kinematics import joint_positions  # noqa: E402
from sim.result import SimulationResult  # noqa: E402

from .definition import Study  # noqa: E402


def draw_mechanism(ax, design: np.ndarray, study: Study, psi: float, color: str, label: str | None = None,
                   alpha: float = 1.0) -> None:
    """Draw the four-bar O-A-B-C of ``design`` (mm) at output angle ``psi`` (rad) on ``ax``."""
    mech = study.mechanism
    pos = joint_positions(design, mech.pivot_c, np.array([psi]), mech.branch)
    pts = np.array([pos[k][0] for k in ("O", "A", "B", "C")])
    ax.plot(pts[:, 0], pts[:, 1], "-o", color=color, lw=2.2, ms=4, alpha=alpha, label=label)


def draw_grounds(ax, study: Study) -> None:
    """Mark the ground pivots O and C."""
    xc, yc = study.mechanism.pivot_c
    ax.plot([0, xc], [0, yc], "k^", ms=9, zorder=5)
    ax.annotate("O", (0, 0), textcoords="offset points", xytext=(6, -12))
    ax.annotate("C", (xc, yc), textcoords="offset points", xytext=(6, -12))


def plot_simulation(result: SimulationResult, study: Study, path: str | Path) -> Path:
    """Torque over the cycle (left) and the mechanism at ψ_start and ψ_end (right), saved to ``path``.

    Parameters
    ----------
    result : SimulationResult
        A simulated design.
    study : Study
        Its study (for the pivot and the stroke).
    path : str or Path
        PNG file to write.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
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
    draw_grounds(ax2, study)
    draw_mechanism(ax2, d, study, study.mechanism.psi_start, "C0", "ψ_start")
    draw_mechanism(ax2, d, study, study.mechanism.psi_end, "C1", "ψ_end")
    ax2.set_aspect("equal")
    ax2.set_xlabel("x (mm)")
    ax2.set_ylabel("y (mm)")
    ax2.set_title(f"|OA|={d[0]:.2f}, |AB|={d[1]:.2f}, |BC|={d[2]:.2f} mm", fontsize=10)
    ax2.legend(loc="best", fontsize=9)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
