"""The figure of a run's progress: every simulation's objective in the order the method asked for it, and the best
value found so far."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from mechopt.sim.figure_file import figure_path, save_figure  # noqa: E402

__all__ = ["plot_convergence"]


def plot_convergence(values: list[float] | np.ndarray, path: str | Path, label: str = "objective",
                     reference: float | None = None, method: str = "") -> Path:
    """Each simulation's objective (a failed one marked at the top) and the best so far, against the simulations.

    Parameters
    ----------
    values : (n,) array_like
        The objective of the run's simulations in the order they were asked for (NaN: failed).
    path : str or Path
        PNG file.
    label : str
        The objective with its unit, for the axis.
    reference : float, optional
        A known optimum (the brute-force ground truth), drawn as a line.
    method : str
        The method, for the title.
    """
    v = np.asarray(values, dtype=float)
    n = np.arange(1, v.size + 1)
    ok = np.isfinite(v)
    best = np.fmin.accumulate(np.where(ok, v, np.nan)) if v.size else v
    path = figure_path(path)
    fig, ax = plt.subplots(figsize=(8.5, 4.4))
    ax.plot(n[ok], v[ok], "o", ms=3.5, mfc="none", color="C0", alpha=0.7, label="a simulation")
    ax.step(n, best, where="post", color="k", lw=1.6, label="best so far")
    if ok.any():
        # The early, far-off values would flatten the part that matters: the axis stops at the upper quartile
        # (or the first best value, when higher), and what lies above is clipped.
        low = float(np.nanmin(v[ok])) if reference is None else min(float(np.nanmin(v[ok])), reference)
        high = max(float(np.percentile(v[ok], 75)), float(best[ok][0]))
        pad = 0.05 * (high - low) if high > low else 1.0
        ax.set_ylim(low - pad, high + pad)
        if (~ok).any():
            ax.plot(n[~ok], np.full((~ok).sum(), high + 0.5 * pad), "x", color="C3", ms=5, label="failed")
    if reference is not None:
        ax.axhline(reference, color="C2", ls="--", lw=1, label="ground truth")
    ax.set_xlabel("simulation, in the order the method asked for it")
    ax.set_ylabel(label)
    ax.set_title(f"Progress of the run{f' ({method})' if method else ''}: {int(ok.sum())} of {v.size} simulations "
                 "succeeded", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    return save_figure(fig, path)
