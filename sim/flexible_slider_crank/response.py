"""What a flexible slider-crank simulation returns, and the paper's normalised response error (Eq. 18)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Response", "normalised_error", "normalised_residuals"]


@dataclass(frozen=True)
class Response:
    """Responses of one design sampled at the paper's instants (SI units).

    Attributes
    ----------
    t : ndarray (n,)
        Sample times (s).
    V, A : ndarray (n,)
        Slider velocity (m/s) and acceleration (m/s²) along x.
    D : ndarray (n,)
        Deflection of the rod's mid-point from the chord A-B (m), positive along the chord's +90° normal.
    s : ndarray (p,)
        Arc lengths from A (m) at which ``shape`` is given.
    shape : ndarray (n, p)
        Deflection of the rod from its chord at ``s`` (m), for drawings.
    engine : str
        ``"modal"`` or ``"exudyn"``.
    seconds : float
        Wall time of the simulation (s).
    """

    t: np.ndarray
    V: np.ndarray
    A: np.ndarray
    D: np.ndarray
    s: np.ndarray
    shape: np.ndarray
    engine: str
    seconds: float


def normalised_error(R: np.ndarray, R_target: np.ndarray) -> float:
    """The paper's Eq. 18: RMS over the samples of (R − R*) divided by the range max R − min R of the design's R.

    Parameters
    ----------
    R, R_target : ndarray (n,)
        A design's response and the target response at the same instants (any unit, the same for both).

    Returns
    -------
    float
        Dimensionless error; ``inf`` if the design's response is constant but differs from the target.
    """
    R = np.asarray(R, dtype=float)
    R_target = np.asarray(R_target, dtype=float)
    rms = float(np.sqrt(np.mean((R - R_target) ** 2)))
    span = float(np.max(R) - np.min(R))
    if span <= 0.0:
        return 0.0 if rms == 0.0 else float("inf")
    return rms / span


def normalised_residuals(R: np.ndarray, R_target: np.ndarray) -> np.ndarray:
    """The per-instant residuals of Eq. 18: (R − R*) / ((max R − min R) sqrt(N)), so that their sum of squares is
    :func:`normalised_error` squared (least-squares problems).

    Parameters
    ----------
    R, R_target : ndarray (n,)
        A design's response and the target response at the same instants (any unit, the same for both).

    Returns
    -------
    ndarray (n,)
        Dimensionless; zeros if the design's response is constant and equal to the target, ``inf`` where it is
        constant and differs (as :func:`normalised_error`).
    """
    R = np.asarray(R, dtype=float)
    diff = R - np.asarray(R_target, dtype=float)
    span = float(np.max(R) - np.min(R))
    if span <= 0.0:
        return np.where(diff == 0.0, 0.0, np.inf)
    return diff / (span * np.sqrt(diff.size))
