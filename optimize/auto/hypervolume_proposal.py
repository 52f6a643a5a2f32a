"""The trade-off search's proposals by expected hypervolume improvement: one GP per objective, the EHVI of
:mod:`~mechopt.optimize.auto.hypervolume_improvement` on the objectives normalised over the current front.

The front is that of the designs that met every limit; its objectives are mapped to z = (f − ideal) / (nadir −
ideal) and the reference point is z = 1.1, the normalisation mechopt reports (:mod:`~mechopt.optimize.pareto`).
A reference at the front's own nadir gives no credit for moving past the front's ends, where the true front may go
on (ZDT3's first piece, ZDT1's ends); so one proposal in k (k objectives) takes the reference beyond the worst
feasible design simulated instead, as Optuna's GPSampler does for all of them.  With two objectives, the candidates
also move only some variables of a front design (as the trust regions' candidates do), which pays there and not
with three (the measurements of both choices: ``docs/guide/trade_offs.md``).
The acquisition is log EHVI + log P(every limit met) + log P(success).  A batch of W workers is chosen one design at
a time, each with the previous ones believed at their posterior mean and added to the front, so that the next one
looks for hypervolume elsewhere (the kriging believer of the single-objective batches).

A problem that declares its objectives' scale (``ideal`` and ``nadir``, as the test problems do and as BoTorch takes
a reference point from its user) fixes the normalisation instead: the same z and reference z = 1.1 as the result's
hypervolume, no extended reference.  A design predicted beyond that reference then earns nothing, so the search is
drawn into the box the user scores; with the front's own scale, DTLZ2-3's designs stayed far from its front (the
measurements: ``docs/guide/trade_offs.md``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mechopt.optimize.auto.acquisition import _candidates, _maximise, not_chosen
from mechopt.optimize.auto.hypervolume_improvement import BoxDecomposition, expected_improvement
from mechopt.optimize.auto.output_models import OutputModels
from mechopt.optimize.pareto import REFERENCE_MARGIN, front_mask

__all__ = ["MOST_BOXES", "affordable", "propose_by_hypervolume"]

#: Largest box decomposition the proposal computes (a front of 140 points in three objectives, of 21 in four);
#: beyond it the trade-off search scalarises (ParEGO), whose cost does not grow with the front.
MOST_BOXES = 20_000

#: Most objectives for which the candidates include front designs with only some variables moved.
SPARSE_UP_TO = 2

#: One proposal in k (the number of objectives) takes the reference beyond the worst feasible design.
EXTEND_EVERY = {2: 2, 3: 3, 4: 4}


def _front_scale(F: np.ndarray, met: np.ndarray,
                 declared: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Front (p, k) of the designs meeting the limits, and the ideal and span that map it to [0, 1] (the declared
    ideal and nadir's when given)."""
    front = F[met][front_mask(F[met])] if met.any() else np.zeros((0, F.shape[1]))
    if declared is not None:
        ideal = np.asarray(declared[0], float)
        return front, ideal, np.maximum(np.asarray(declared[1], float) - ideal, 1e-300)
    source = front if front.shape[0] > 1 else F
    ideal = source.min(axis=0)
    span = np.ptp(source, axis=0)
    return front, ideal, np.where(span > 0, span, 1.0)


def affordable(F: np.ndarray, met: np.ndarray) -> bool:
    """Whether the box decomposition of the current front stays within :data:`MOST_BOXES`."""
    front = F[met][front_mask(F[met])] if met.any() else F[:0]
    return (front.shape[0] + 1) ** (F.shape[1] - 1) <= MOST_BOXES


def propose_by_hypervolume(U: np.ndarray, F: np.ndarray, met: np.ndarray, objectives: OutputModels, q: int,
                           rng: np.random.Generator, allowed: Callable[[np.ndarray], np.ndarray],
                           log_feasible: Callable[[np.ndarray], np.ndarray] | None,
                           margins: Callable[[np.ndarray], np.ndarray] | None = None,
                           declared: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """``q`` designs of the unit cube maximising log EHVI (+ log P(limits met, success)).

    Parameters
    ----------
    U : (n, d) ndarray
        Designs simulated successfully (unit cube).
    F : (n, k) ndarray
        Their minimised objectives.
    met : (n,) bool ndarray
        Which of them met every limit.
    objectives : OutputModels
        The objectives' GPs, fitted to U, F.
    q : int
        Designs wanted.
    rng : Generator
    allowed : callable
        ``allowed(C) -> bool (m,)``: designs that may be simulated.
    log_feasible : callable, optional
        Log-probability of meeting the limits and of a successful simulation.
    margins : callable, optional
        Declared constraints' margins in the unit cube (the polish may end on one).
    declared : (ideal (k,), nadir (k,)), optional
        The objectives' scale the problem declares (minimised sense): the normalisation, instead of the front's.

    Returns
    -------
    (p, d) ndarray
        p <= q designs (fewer when no allowed candidate is left).
    """
    front, ideal, span = _front_scale(F, met, declared)
    Z = (front - ideal) / span
    reference = np.full(F.shape[1], REFERENCE_MARGIN)
    # One proposal in k extends the front: its reference lies beyond the worst feasible design.
    period = 0 if declared is not None else EXTEND_EVERY.get(F.shape[1], 0)
    extended = reference if not period or not met.any() else \
        np.maximum(reference, ((F[met] - ideal) / span).max(axis=0) + REFERENCE_MARGIN - 1.0)
    d = U.shape[1]
    lo, hi = np.zeros(d), np.ones(d)
    front_designs = U[met][front_mask(F[met])] if met.any() else U
    chosen: list[np.ndarray] = []
    has_front = Z.shape[0] > 0
    for i in range(q):
        extend = period > 0 and (U.shape[0] + i) % period == period - 1
        boxes = BoxDecomposition.of(Z, extended if extend else reference)

        def score(C: np.ndarray, boxes: BoxDecomposition = boxes) -> np.ndarray:
            # Until a design meets the limits there is no front: the probability of meeting them chooses.
            s = np.zeros(np.atleast_2d(C).shape[0])
            if has_front:
                mean, sd = objectives.predict(C)
                s = np.log(np.maximum(expected_improvement(boxes, (mean - ideal) / span, sd / span), 1e-300))
            return s + log_feasible(C) if log_feasible is not None else s

        centre = front_designs[rng.integers(front_designs.shape[0])]
        C = _candidates(lo, hi, centre, 1024, rng, sparse=F.shape[1] <= SPARSE_UP_TO)
        x = _maximise(score, lo, hi, C, not_chosen(allowed, chosen), 3, margins)
        if x is None:
            break
        chosen.append(x)
        if has_front:
            believed, _ = objectives.predict(x[None, :])
            Z = np.vstack([Z, (believed - ideal) / span])
            Z = Z[front_mask(Z)]
    return np.array(chosen).reshape(-1, d)
