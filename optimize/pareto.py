"""The Pareto front of simulated designs and its hypervolume (moocore's non-dominated filter and hypervolume).

Normalisation
-------------
A hypervolume depends on the scale of each objective and on the reference point.  :func:`normalisation` states the
one mechopt reports: each minimised objective mapped to z = (f − ideal) / (nadir − ideal), where ideal and nadir are
the least and the largest value of that objective over the front, and the reference point z = 1.1 in every
objective (pymoo's and BoTorch's habit of a reference a little beyond the nadir).  A problem may fix the
normalisation itself with ``ideal`` and ``reference_point`` attributes (objective units, minimised sense), which
makes hypervolumes of different runs comparable; then z = (f − ideal) / (reference − ideal) and the reference is 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import moocore
import numpy as np

__all__ = ["Normalisation", "front_mask", "hypervolume", "hypervolume_trace", "normalisation"]

#: Reference point of the default normalisation: 10 % of the front's range beyond its nadir.
REFERENCE_MARGIN = 1.1


@dataclass(frozen=True)
class Normalisation:
    """How objectives are scaled before a hypervolume is measured.

    Attributes
    ----------
    ideal : (k,) ndarray
        Objective values mapped to 0 (minimised sense, objective units).
    scale : (k,) ndarray
        Objective spans mapped to 1.
    reference : (k,) ndarray
        Reference point in normalised coordinates.
    description : str
        One sentence for reports.
    """

    ideal: np.ndarray
    scale: np.ndarray
    reference: np.ndarray
    description: str

    def __call__(self, F: np.ndarray) -> np.ndarray:
        """Normalised objectives of F (n, k)."""
        return (np.atleast_2d(F) - self.ideal) / self.scale

    @property
    def reference_point(self) -> np.ndarray:
        """The reference point in objective units (minimised sense)."""
        return self.ideal + self.reference * self.scale


def front_mask(F: np.ndarray) -> np.ndarray:
    """Designs (n,) of F (n, k, minimised, finite) that no other design dominates; of equal points the first only."""
    F = np.atleast_2d(np.asarray(F, dtype=float))
    if not F.shape[0]:
        return np.zeros(0, dtype=bool)
    mask = np.asarray(moocore.is_nondominated(F, keep_weakly=True), dtype=bool)
    _, first = np.unique(F, axis=0, return_index=True)
    unique = np.zeros(F.shape[0], dtype=bool)
    unique[first] = True
    return mask & unique


def normalisation(front: np.ndarray, ideal: np.ndarray | None = None,
                  nadir: np.ndarray | None = None) -> Normalisation:
    """The normalisation of :mod:`this module <mechopt.optimize.pareto>` for a front (n, k) of minimised values.

    Parameters
    ----------
    front : (n, k) ndarray
        Non-dominated values (at least one row unless both other arguments are given).
    ideal, nadir : (k,) ndarray, optional
        Fixed by the problem (its known front): both, or neither.
    """
    if ideal is not None and nadir is not None:
        ideal, nadir = np.asarray(ideal, float), np.asarray(nadir, float)
        return Normalisation(ideal, np.maximum(nadir - ideal, 1e-300), np.full(ideal.size, REFERENCE_MARGIN),
                             f"z = (f - ideal) / (nadir - ideal) with the problem's ideal {_fmt(ideal)} and nadir "
                             f"{_fmt(nadir)}; reference point z = {REFERENCE_MARGIN:g} in every objective")
    front = np.atleast_2d(front)
    lo, hi = front.min(axis=0), front.max(axis=0)
    span = np.where(hi > lo, hi - lo, np.maximum(np.abs(lo), 1.0))
    return Normalisation(lo, span, np.full(lo.size, REFERENCE_MARGIN),
                         f"z = (f - ideal) / (nadir - ideal) with the front's ideal {_fmt(lo)} and nadir "
                         f"{_fmt(lo + span)}; reference point z = {REFERENCE_MARGIN:g} in every objective")


def _fmt(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:.4g}" for x in v) + ")"


def hypervolume(F: np.ndarray, norm: Normalisation) -> float:
    """Hypervolume (normalised units) dominated by designs F (n, k, minimised) up to the reference point; points
    beyond the reference add nothing."""
    Z = norm(np.asarray(F, dtype=float).reshape(-1, norm.ideal.size))
    Z = Z[np.all(Z < norm.reference, axis=1)]
    if not Z.shape[0]:
        return 0.0
    return float(moocore.hypervolume(Z, ref=norm.reference))


def hypervolume_trace(F: np.ndarray, feasible: np.ndarray, norm: Normalisation) -> np.ndarray:
    """Hypervolume of the feasible designs among the first i, for i = 1..n (simulation order), in normalised units.

    Parameters
    ----------
    F : (n, k) ndarray
        Minimised objectives of every design in the order simulated (NaN: failed).
    feasible : (n,) bool ndarray
        Designs that met every margin and limit.
    norm : Normalisation
        The normalisation.
    """
    F = np.atleast_2d(np.asarray(F, dtype=float))
    ok = np.asarray(feasible, dtype=bool) & np.all(np.isfinite(F), axis=1)
    trace = np.zeros(F.shape[0])
    front = np.zeros((0, F.shape[1]))
    value = 0.0
    for i in range(F.shape[0]):
        if ok[i] and not np.any(np.all(front <= F[i], axis=1)):
            front = np.vstack([front[~np.all(F[i] <= front, axis=1)], F[i]])
            value = hypervolume(front, norm)
        trace[i] = value
    return trace
