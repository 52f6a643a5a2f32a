"""Validation of a model on held-out lines in other directions than its own (paper Fig. 16)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from mechopt.optimize.sparse.model import ObjectiveModel
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace

__all__ = ["Validation", "validate", "validation_lines"]


@dataclass
class Validation:
    """Held-out simulations against the model.

    Attributes
    ----------
    lines : list of dict
        Per line: ``designs``, ``simulated``, ``predicted``.
    rmse, rmse_low, max_error : float
        RMS error over all points, over those with objective <= 2 f_min, largest error (objective units).
    f_min : float
        The reference minimum the relative figures use: the best simulated design of the run.
    n_points : int
        Held-out simulations that succeeded.
    spread : float
        Range (max − min) of the held-out simulations: the scale of an objective whose minimum is 0.
    """

    lines: list[dict]
    rmse: float
    rmse_low: float
    max_error: float
    f_min: float
    n_points: int
    spread: float = float("nan")

    @property
    def rmse_pct(self) -> float:
        """RMSE as a percentage of |f_min| (NaN when there is no point or f_min is 0)."""
        return 100 * self.rmse / abs(self.f_min) if self.n_points and self.f_min else float("nan")

    @property
    def rmse_pct_of_range(self) -> float:
        """RMSE as a percentage of the held-out values' range."""
        return 100 * self.rmse / self.spread if self.n_points and self.spread > 0 else float("nan")

    def relative_text(self, unit: str = "") -> str:
        """The RMSE as a share of the held-out values' range, with that range in the objective's ``unit``.

        Always the range, never the best value: a percentage of a value near 0 says nothing ("RMSE 33 % of the
        best simulated value −0.058").
        """
        unit = f" {unit}" if unit else ""
        return f"{self.rmse_pct_of_range:.2f} % of the held-out values' range {self.spread:.4g}{unit}"

    def summary(self) -> dict:
        """JSON-able summary (lines with their points)."""
        return {**asdict(self), "rmse_pct_of_f_min": self.rmse_pct, "rmse_pct_of_range": self.rmse_pct_of_range}


def validation_lines(model: ObjectiveModel, space: ModelSpace, n_lines: int, n_points: int,
                     seed: int) -> list[np.ndarray]:
    """Held-out lines inside the model's hull ∩ feasible region, at least 30° from the model's Δ (designs)."""
    rng = np.random.default_rng(seed + 1000)
    d = space.dim
    delta = model.plan.direction / np.linalg.norm(model.plan.direction)
    lo_u, hi_u = space.lower_u, space.upper_u
    cloud = rng.uniform(lo_u, hi_u, size=(40_000, d))
    cloud = cloud[model.model.contains(cloud) & space.feasible_u(cloud)]
    lines: list[np.ndarray] = []
    tries = 0
    extent = float(np.linalg.norm(hi_u - lo_u))
    # A thin hull (a few lines of the paper's plan) rejects most directions: tries are cheap, no simulation.
    while len(lines) < n_lines and tries < max(500, 50 * n_lines) and len(cloud):
        tries += 1
        u = rng.standard_normal(d) * (hi_u - lo_u)
        u /= np.linalg.norm(u)
        if abs(u @ delta) > np.cos(np.radians(30)):
            continue
        through = cloud[rng.integers(len(cloud))]
        s = np.linspace(-extent, extent, 4001)
        pts = through + s[:, None] * u
        ok = model.model.contains(pts) & space.feasible_u(pts)
        i0 = int(np.argmin(np.abs(s)))
        if not ok[i0]:
            continue
        a, b = i0, i0
        while a > 0 and ok[a - 1]:
            a -= 1
        while b < len(s) - 1 and ok[b + 1]:
            b += 1
        if s[b] - s[a] < 0.1 * extent:
            continue
        ts = np.linspace(s[a], s[b], n_points)
        lines.append(space.from_u(through + ts[:, None] * u))
    return lines


def validate(model: ObjectiveModel, space: ModelSpace, sampler: Sampler, n_lines: int, n_points: int, seed: int,
             f_min: float) -> Validation:
    """Simulate held-out lines and compare with the model.

    Parameters
    ----------
    f_min : float
        The best simulated objective of the run: the one reference the relative figures use everywhere.
    """
    records, sims, preds = [], [], []
    for j, designs in enumerate(validation_lines(model, space, n_lines, n_points, seed)):
        sim = sampler(designs, desc=f"validation line {j + 1}/{n_lines}")
        pred = model.predict(designs)
        ok = np.isfinite(sim)
        records.append({"designs": designs[ok].tolist(), "simulated": sim[ok].tolist(),
                        "predicted": pred[ok].tolist()})
        sims.append(sim[ok])
        preds.append(pred[ok])
    sim = np.concatenate(sims) if sims else np.array([])
    err = (np.concatenate(preds) if preds else np.array([])) - sim
    low = sim <= 2 * f_min if f_min > 0 else np.ones(sim.size, dtype=bool)
    nan = float("nan")
    return Validation(
        lines=records,
        rmse=float(np.sqrt(np.mean(err**2))) if err.size else nan,
        rmse_low=float(np.sqrt(np.mean(err[low] ** 2))) if low.any() else nan,
        max_error=float(np.max(np.abs(err))) if err.size else nan,
        f_min=float(f_min),
        n_points=int(sim.size),
        spread=float(np.ptp(sim)) if sim.size else nan,
    )
