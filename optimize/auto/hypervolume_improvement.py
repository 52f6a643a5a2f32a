"""Expected hypervolume improvement (EHVI) of a design whose objectives are independent Gaussians, in closed form.

The region a new point y can add to the hypervolume of a front P (minimised objectives, reference point r) is
A = {z <= r : no p in P weakly dominates z}.  It is cut into boxes over a grid of the first k − 1 axes, whose lines
are the front's coordinates: every box [l, u] of that grid is either dominated or not at every point, and along the
last axis the part of A above it is one interval, from −∞ to the least last coordinate of the front points that
dominate l in the first k − 1 axes (or r_k).  The hypervolume improvement of y is then

    HVI(y) = Σ_boxes Π_j (u_j − max(l_j, y_j))⁺,

and with independent Y_j ~ N(μ_j, σ_j²) the expectation of each product is the product of the expectations,

    E[(u − max(l, Y))⁺] = (u − l) Φ(a) + (u − μ)(Φ(b) − Φ(a)) + σ (φ(b) − φ(a)),   a = (l − μ)/σ, b = (u − μ)/σ,

(Emmerich, Giannakoglou & Naujoks 2006; the box form of Yang et al. 2019).  The boxes number (n + 1)^(k−1) for a
front of n points: n + 1 in two objectives, (n + 1)² in three.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

__all__ = ["BoxDecomposition", "expected_improvement", "hypervolume_improvement"]

_INV_SQRT_2PI = 1.0 / np.sqrt(2.0 * np.pi)

#: Candidates per block: the gather of the last axis's factor is (block, boxes) floats.
_BLOCK = 256


@dataclass(frozen=True)
class BoxDecomposition:
    """The non-dominated region of a front below a reference point, as boxes.

    Attributes
    ----------
    edges : list of (n_j + 2,) ndarray
        Grid lines of each of the first k − 1 axes: −∞, the front's coordinates below the reference, the reference.
    top_values : (t,) ndarray
        Distinct upper ends of the boxes along the last axis.
    top_index : (n_1 + 1, ..., n_{k−1} + 1) int ndarray
        Index in ``top_values`` of each box's upper end along the last axis.
    """

    edges: list[np.ndarray]
    top_values: np.ndarray
    top_index: np.ndarray

    @classmethod
    def of(cls, front: np.ndarray, reference: np.ndarray) -> BoxDecomposition:
        """Boxes of the region front (n, k) does not dominate below ``reference`` (k,); k >= 2."""
        reference = np.asarray(reference, float)
        P = np.atleast_2d(np.asarray(front, float))
        P = P[np.all(P < reference, axis=1)] if P.size else np.zeros((0, reference.size))
        k = reference.size
        edges = [np.concatenate([[-np.inf], np.unique(P[:, j]), [reference[j]]]) for j in range(k - 1)]
        lower = np.stack(np.meshgrid(*[e[:-1] for e in edges], indexing="ij"), axis=-1).reshape(-1, k - 1)
        if P.shape[0]:
            covers = np.all(P[None, :, : k - 1] <= lower[:, None, :], axis=2)
            top = np.min(np.where(covers, P[None, :, k - 1], reference[k - 1]), axis=1)
        else:
            top = np.full(lower.shape[0], reference[k - 1])
        values, index = np.unique(top, return_inverse=True)
        return cls(edges, values, index.reshape([e.size - 1 for e in edges]))

    @property
    def count(self) -> int:
        """Number of boxes."""
        return int(self.top_index.size)


def _box_factor(lower: np.ndarray, upper: np.ndarray, mean: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """E[(u − max(l, Y))⁺] (q, b) for Y ~ N(mean, sd²) (q,) and intervals [lower, upper] (b,), lower may be −∞."""
    mu, s = mean[:, None], sd[:, None]
    b = (upper[None, :] - mu) / s
    with np.errstate(invalid="ignore"):
        a = (lower[None, :] - mu) / s
        Phi_a, Phi_b = ndtr(a), ndtr(b)
        phi_a, phi_b = _INV_SQRT_2PI * np.exp(-0.5 * a * a), _INV_SQRT_2PI * np.exp(-0.5 * b * b)
        width = np.where(np.isfinite(lower), upper - lower, 0.0)[None, :]
    value = width * Phi_a + (upper[None, :] - mu) * (Phi_b - Phi_a) + s * (phi_b - phi_a)
    return np.maximum(value, 0.0)


def expected_improvement(boxes: BoxDecomposition, mean: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """EHVI (q,) of designs whose objectives are independent N(mean, sd²), mean and sd (q, k) in the front's units."""
    mean, sd = np.atleast_2d(mean), np.maximum(np.atleast_2d(sd), 1e-12)
    q, k = mean.shape
    out = np.empty(q)
    letters = "abc"[: k - 1]
    spec = ",".join(f"n{c}" for c in letters) + f",n{letters}->n"
    for start in range(0, q, _BLOCK):
        rows = slice(start, start + _BLOCK)
        factors = [_box_factor(e[:-1], e[1:], mean[rows, j], sd[rows, j]) for j, e in enumerate(boxes.edges)]
        last = _box_factor(np.full(boxes.top_values.size, -np.inf), boxes.top_values, mean[rows, k - 1],
                           sd[rows, k - 1])
        out[rows] = np.einsum(spec, *factors, last[:, boxes.top_index], optimize=True)
    return out


def hypervolume_improvement(boxes: BoxDecomposition, Y: np.ndarray) -> np.ndarray:
    """HVI (q,) of points Y (q, k) over the front the boxes were cut from (the EHVI's deterministic limit)."""
    Y = np.atleast_2d(Y)
    return expected_improvement(boxes, Y, np.full(Y.shape, 1e-12))
