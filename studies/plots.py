"""Figures of mechopt (matplotlib, headless): torque curves, mechanism drawings, feasible regions, validation."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mechopt.sim.fourbar.kinematics import joint_positions  # noqa: E402
from mechopt.sim.fourbar.result import SimulationResult  # noqa: E402

from .definition import Study  # noqa: E402


def _save(fig, path: Path) -> Path:
    """Write a finished figure (PNG, 110 dpi: readable at 100 % zoom) and release it."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


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
    return _save(fig, path)


_CONSTRAINTS = (
    ("assembly_start_mm", "assemblable at ψ_start", "C0"),
    ("assembly_end_mm", "assemblable at ψ_end", "C3"),
    ("monotonic_deg", "crank monotonic", "C2"),
    ("toggle_deg", "toggle margin", "C4"),
)


def plot_feasible_slices(study: Study, path: str | Path, oa_values: list[float] | None = None,
                         marks: dict[str, np.ndarray] | None = None, n: int = 260) -> Path:
    """The feasible region in (|AB|, |BC|) slices at fixed |OA|, with each constraint's boundary (paper Fig. 7, 12).

    Parameters
    ----------
    study : Study
        The study (region and mechanism).
    path : str or Path
        PNG file to write.
    oa_values : list of float, optional
        |OA| of the slices (mm); default: the region's lower end, middle and upper end.
    marks : dict, optional
        Designs to mark (name -> (3,) mm), drawn on the slice nearest their |OA|.
    n : int
        Grid resolution per axis.
    """
    from mechopt.sim.fourbar.feasibility import check_feasibility

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    (oa_lo, oa_hi), (ab_lo, ab_hi), (bc_lo, bc_hi) = study.region
    if oa_values is None:
        oa_values = [oa_lo, 0.5 * (oa_lo + oa_hi), oa_hi]
    ab = np.linspace(ab_lo, ab_hi, n)
    bc = np.linspace(bc_lo, bc_hi, n)
    AB, BC = np.meshgrid(ab, bc, indexing="ij")
    fig, axes = plt.subplots(1, len(oa_values), figsize=(5.2 * len(oa_values), 4.8), squeeze=False)
    for ax, oa in zip(axes[0], oa_values, strict=True):
        designs = np.column_stack([np.full(AB.size, oa), AB.ravel(), BC.ravel()])
        report = check_feasibility(designs, study.mechanism)
        feasible = report.feasible.reshape(AB.shape)
        ax.contourf(AB, BC, feasible.astype(float), levels=[0.5, 1.5], colors=["#cfe8cf"])
        handles = []
        for column, label, color in _CONSTRAINTS:
            values = np.nan_to_num(getattr(report, column).reshape(AB.shape), nan=-1.0)
            if values.min() < 0 < values.max():
                ax.contour(AB, BC, values, levels=[0.0], colors=[color], linewidths=1.8)
                handles.append(plt.Line2D([], [], color=color, lw=1.8, label=f"{label} = 0"))
        for name, d in (marks or {}).items():
            if abs(d[0] - oa) <= 0.5 * (oa_hi - oa_lo) / max(len(oa_values) - 1, 1):
                ax.plot(d[1], d[2], "k*" if "optimum" in name else "ko", ms=10)
                ax.annotate(f"{name} (|OA|={d[0]:.1f})", (d[1], d[2]), textcoords="offset points", xytext=(6, 4),
                            fontsize=8)
        handles.append(plt.Rectangle((0, 0), 1, 1, color="#cfe8cf", label="feasible"))
        ax.set_xlabel("|AB| (mm)")
        ax.set_ylabel("|BC| (mm)")
        ax.set_title(f"|OA| = {oa:.1f} mm", fontsize=10)
        ax.grid(alpha=0.25)
    fig.legend(handles=handles, fontsize=9, loc="lower center", ncol=len(handles), frameon=False)
    fig.suptitle(f"Feasible designs of study '{study.name}' (slices at fixed |OA|)", fontsize=11)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return _save(fig, path)


def plot_feasible_3d(study: Study, path: str | Path, lines: list[np.ndarray] | None = None,
                     hull_points: np.ndarray | None = None, marks: dict[str, np.ndarray] | None = None,
                     n_points: int = 6000, seed: int = 0) -> Path:
    """3-D view of the feasible region with the sampling lines and their convex hull (paper Fig. 12 right, 15).

    Parameters
    ----------
    study : Study
        The study.
    path : str or Path
        PNG file to write.
    lines : list of (k, 3) ndarray, optional
        Sampled points of each line, designs in mm.
    hull_points : (m, 3) ndarray, optional
        Points whose convex hull is drawn (the lines' end points), mm.
    marks : dict, optional
        Designs to mark (name -> (3,) mm).
    n_points : int
        Random feasible designs shown as a cloud.
    """
    from mechopt.sim.fourbar.feasibility import feasible_mask
    from scipy.spatial import ConvexHull

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    cloud = rng.uniform(study.region[:, 0], study.region[:, 1], size=(8 * n_points, 3))
    cloud = cloud[feasible_mask(cloud, study.mechanism)][:n_points]
    fig = plt.figure(figsize=(8.5, 7))
    ax = fig.add_subplot(projection="3d")
    ax.scatter(cloud[:, 0], cloud[:, 1], cloud[:, 2], s=3, c="#2e8b57", alpha=0.18, depthshade=False,
               label="feasible designs")
    for i, pts in enumerate(lines or []):
        ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], ".-", color="C3", ms=2.5, lw=1,
                label="sampling lines" if i == 0 else None)
    if hull_points is not None and len(hull_points) >= 4:
        hull = ConvexHull(hull_points)
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        tris = [hull_points[s] for s in hull.simplices]
        ax.add_collection3d(Poly3DCollection(tris, facecolor="C0", alpha=0.08, edgecolor="C0", linewidth=0.2))
    for name, d in (marks or {}).items():
        ax.scatter([d[0]], [d[1]], [d[2]], s=80, marker="*" if "optimum" in name else "o", color="k")
        ax.text(d[0], d[1], d[2], f"  {name}", fontsize=8)
    ax.set_xlabel("|OA| (mm)")
    ax.set_ylabel("|AB| (mm)")
    ax.set_zlabel("|BC| (mm)")
    ax.view_init(elev=22, azim=-58)
    ax.set_title(f"Feasible region of '{study.name}', sampling lines and their convex hull", fontsize=10)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def plot_torque_comparison(results: dict[str, SimulationResult], path: str | Path) -> Path:
    """Motor torque over the cycle of several designs on one axis (paper Fig. 2)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
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
    return _save(fig, path)


def plot_mechanisms(designs: dict[str, np.ndarray], study: Study, path: str | Path) -> Path:
    """Each design drawn at ψ_start and ψ_end, side by side, on a common scale."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, len(designs), figsize=(5.5 * len(designs), 4.2), squeeze=False, sharey=True)
    for ax, (name, d) in zip(axes[0], designs.items(), strict=True):
        draw_grounds(ax, study)
        draw_mechanism(ax, d, study, study.mechanism.psi_start, "C0", "ψ_start")
        draw_mechanism(ax, d, study, study.mechanism.psi_end, "C1", "ψ_end")
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        ax.set_title(f"{name}: |OA|={d[0]:.2f}, |AB|={d[1]:.2f}, |BC|={d[2]:.2f} mm", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="lower left")
    axes[0][0].set_ylabel("y (mm)")
    fig.tight_layout()
    return _save(fig, path)


def animate_cycle(result: SimulationResult, study: Study, path: str | Path, frames: int = 40) -> Path:
    """Animated GIF of a design through its cycle, with the torque trace growing beside it."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mech = study.mechanism
    idx = np.linspace(0, result.t.size - 1, frames).astype(int)
    pos = joint_positions(result.design, mech.pivot_c, result.psi[idx], mech.branch)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.6), gridspec_kw={"width_ratios": [1.2, 1]})
    draw_grounds(ax1, study)
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

    anim = FuncAnimation(fig, update, frames=frames, blit=True)
    anim.save(path, writer=PillowWriter(fps=12))
    plt.close(fig)
    return path


def plot_validation(lines: list[dict], path: str | Path, fit_lines: list[tuple[np.ndarray, np.ndarray]] | None = None,
                    model=None) -> Path:
    """Simulated T_RMS against the model along fitting and held-out lines (paper Fig. 16).

    Parameters
    ----------
    lines : list of dict
        Held-out lines: ``designs_mm``, ``simulated``, ``predicted``.
    path : str or Path
        PNG file to write.
    fit_lines : list of (designs, values), optional
        The fitting lines, drawn too (the model interpolates them).
    model : optional
        The model, to draw its curve along the fitting lines.
    """
    from .design_space import to_u

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(11, 4.8))
    x0 = 0
    for i, (designs, values) in enumerate(fit_lines or []):
        x = x0 + np.arange(len(values))
        ax.plot(x, values, "o", ms=3, color="C3", label="fitting lines (simulated)" if i == 0 else None)
        if model is not None:
            ax.plot(x, model.predict(to_u(designs)), "-", color="C0", lw=1.2, label="model" if i == 0 else None)
        x0 += len(values) + 4
    for i, line in enumerate(lines):
        sim, pred = np.asarray(line["simulated"]), np.asarray(line["predicted"])
        x = x0 + np.arange(len(sim))
        ax.plot(x, sim, "s", ms=3, color="C4", label="held-out lines (simulated)" if i == 0 else None)
        ax.plot(x, pred, "-", color="C0", lw=1.2, label=None if fit_lines else ("model" if i == 0 else None))
        x0 += len(sim) + 4
    ax.set_xlabel("sample along the lines, one line after the other")
    ax.set_ylabel("T_RMS (N·m)")
    ax.set_title("Global model against simulations on its fitting lines and on held-out lines", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return _save(fig, path)
