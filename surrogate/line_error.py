"""The model's error ACROSS lines: leave-one-line-out blends and their disagreement.

Along a line the exponential fit reproduces the samples closely; between lines the model is a Chebyshev blend of the
line models, accurate only for features wider than the line spacing.  Removing line i and blending the other l − 1
line models (a new :class:`~surrogate.blending.ChebyshevBlend` on their nodes; the 1-D fits are unchanged, since each
depends only on its own line's samples) predicts line i's samples as if they had not been taken:

* :func:`leave_one_line_out` gives, per line, the RMS of those predictions' errors — a held-out error of the blend at
  the data's own spacing, which needs no extra simulation;
* :func:`blend_spread` gives, at any point, the RMS difference between the l leave-one-out blends and the full
  blend: large where the model depends on a single line (between lines, near the hull's corners), small where
  neighbouring lines agree.  ``model − κ·spread`` is then an optimistic bound used to decide where to look again.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mechopt.surrogate.blending import ChebyshevBlend
from mechopt.surrogate.errors import SurrogateError
from mechopt.surrogate.model import SparseExponentialModel


@dataclass(frozen=True, eq=False)
class LineOutError:
    """Leave-one-line-out errors of a fitted model.

    Attributes
    ----------
    rms : (l,) array
        Per line, the RMS difference between the blend of the other lines and line i's samples (data units);
        NaN when the other nodes admit no well-conditioned blend.
    value_range : float
        max − min of all sampled values (data units), the scale of :attr:`relative`.
    """

    rms: np.ndarray
    value_range: float

    @property
    def relative(self) -> np.ndarray:
        """Per-line RMS error divided by the range of the sampled values."""
        return self.rms / self.value_range if self.value_range > 0 else np.full_like(self.rms, np.nan)

    @property
    def median(self) -> float:
        """Median relative error over the lines (NaN lines ignored)."""
        rel = self.relative
        return float(np.nanmedian(rel)) if np.isfinite(rel).any() else float("nan")

    @property
    def max(self) -> float:
        """Largest relative error over the lines."""
        rel = self.relative
        return float(np.nanmax(rel)) if np.isfinite(rel).any() else float("nan")


def _reduced_blends(model: SparseExponentialModel) -> list[tuple[np.ndarray, ChebyshevBlend] | None]:
    """For every line i: (indices of the other lines, their blend), or None if that blend is ill-conditioned."""
    nodes = model.plan.line_nodes()
    out: list[tuple[np.ndarray, ChebyshevBlend] | None] = []
    for i in range(model.l):
        others = np.delete(np.arange(model.l), i)
        try:
            out.append((others, ChebyshevBlend(nodes[others], cond_max=model.cond_max)))
        except SurrogateError:
            out.append(None)
    return out


def leave_one_line_out(model: SparseExponentialModel, values: Sequence[Any]) -> LineOutError:
    """Predict every line's samples from the other lines' models.

    Parameters
    ----------
    model : SparseExponentialModel
        Fitted model with l >= 3 lines.
    values : sequence of l arrays
        Line i's sampled values at k = k_ranges[i, 0] .. k_ranges[i, 1] (the data the model was fitted to).

    Returns
    -------
    LineOutError
    """
    model._require_fit()
    if model.l < 3:
        raise SurrogateError(f"leave-one-line-out needs at least 3 lines, got {model.l}")
    if len(values) != model.l:
        raise SurrogateError(f"the model has {model.l} lines but {len(values)} value sets were given")
    plan = model.plan
    rms = np.full(model.l, np.nan)
    all_values = []
    for i, reduced in enumerate(_reduced_blends(model)):
        k0, k1 = plan.k_ranges[i]
        v = np.asarray(values[i], dtype=float).reshape(-1)
        if v.size != k1 - k0 + 1:
            raise SurrogateError(f"line {i}: {v.size} values for the sampled range k = {k0}..{k1}")
        all_values.append(v)
        if reduced is None:
            continue
        others, blend = reduced
        P, d = plan.coordinates(plan.points(i, np.arange(k0, k1 + 1)))
        pred = np.einsum("nj,nj->n", blend.lagrange(P), model.line_values(d)[:, others])
        rms[i] = float(np.sqrt(np.mean((pred - v) ** 2)))
    flat = np.concatenate(all_values)
    return LineOutError(rms, float(np.ptp(flat)))


def blend_spread(model: SparseExponentialModel, X: Any) -> np.ndarray:
    """RMS difference between the leave-one-line-out blends and the full blend at points X.

    Parameters
    ----------
    model : SparseExponentialModel
        Fitted model with l >= 3 lines.
    X : (n, d) array
        Points (caller's units).

    Returns
    -------
    (n,) array
        Data units; zero on every line where all reduced blends reproduce the full one, growing between lines.
    """
    model._require_fit()
    pts = np.atleast_2d(np.asarray(X, dtype=float))
    P, d = model.plan.coordinates(pts)
    F = model.line_values(d)
    full = np.einsum("ni,ni->n", model.blend.lagrange(P), F)
    acc = np.zeros(pts.shape[0])
    count = 0
    for reduced in _reduced_blends(model):
        if reduced is None:
            continue
        others, blend = reduced
        acc += (np.einsum("nj,nj->n", blend.lagrange(P), F[:, others]) - full) ** 2
        count += 1
    if count == 0:
        raise SurrogateError("no leave-one-line-out blend is well-conditioned; the spread is undefined")
    return np.sqrt(acc / count)
