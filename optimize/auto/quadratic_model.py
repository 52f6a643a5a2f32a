"""A full quadratic model of the objective around a design, fitted to the designs nearest it, and its minimiser in a
box trust region (the local model of Powell's methods: UOBYQA, NEWUOA, BOBYQA).

A Gaussian process with one length-scale per variable sees a rotated, ill-conditioned valley as an axis-aligned
bowl whose short length-scales are set by the valley's steep walls; along the valley's floor it then expects nothing
from a move it has not sampled near.  A quadratic with every cross term holds the valley's orientation and each
direction's curvature: its Hessian's eigenvectors are the valley's axes, its eigenvalues their curvatures.

With ``p = (d + 1)(d + 2)/2`` designs or more, the model is the least-squares fit of every coefficient (an
interpolation at exactly p well-placed designs: a quadratic objective is recovered exactly).  Its leave-one-out
R² (:func:`leave_one_out_r2`) says whether a quadratic describes the designs at all.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

__all__ = ["QuadraticModel", "fit_quadratic", "leave_one_out_r2", "n_coefficients"]


def n_coefficients(dim: int) -> int:
    """Coefficients of a full quadratic in ``dim`` variables: (d + 1)(d + 2)/2."""
    return (dim + 1) * (dim + 2) // 2


def _basis(Z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The linear columns [1, z] (m, d + 1), the curvature columns (m, d(d + 1)/2) of ½ z_i² (diagonal) and z_i z_j
    (i < j), and the index pairs (i, j) of the curvature columns."""
    m, d = Z.shape
    i, j = np.triu_indices(d)
    Q = Z[:, i] * Z[:, j]
    Q[:, i == j] *= 0.5
    return np.hstack([np.ones((m, 1)), Z]), Q, np.vstack([i, j])


@dataclass(frozen=True)
class QuadraticModel:
    """m(u) = value + gradientᵀ(u − centre) + ½ (u − centre)ᵀ hessian (u − centre), u in the unit cube.

    Attributes
    ----------
    centre : (d,) ndarray
        Design the model is expanded about (unit cube).
    value : float
        Model value at the centre (objective's units).
    gradient : (d,) ndarray
        Gradient at the centre (objective's units per unit of the cube).
    hessian : (d, d) ndarray
        Symmetric Hessian (objective's units per unit of the cube squared).
    """

    centre: np.ndarray
    value: float
    gradient: np.ndarray
    hessian: np.ndarray

    def __call__(self, U: np.ndarray) -> np.ndarray:
        """Model values at designs U (m, d)."""
        S = np.atleast_2d(U) - self.centre
        return self.value + S @ self.gradient + 0.5 * np.sum((S @ self.hessian) * S, axis=1)

    def minimiser(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """The model's minimiser in the box [lo, hi] reached by L-BFGS-B from the centre (a local one where the
        model is not convex)."""
        def fun(u: np.ndarray) -> tuple[float, np.ndarray]:
            s = u - self.centre
            hs = self.hessian @ s
            return float(self.value + s @ self.gradient + 0.5 * s @ hs), self.gradient + hs

        start = np.clip(self.centre, lo, hi)
        res = minimize(fun, start, jac=True, method="L-BFGS-B", bounds=list(zip(lo, hi, strict=True)),
                       options={"maxiter": 200, "ftol": 1e-15, "gtol": 1e-12})
        return np.clip(res.x, lo, hi)


def fit_quadratic(U: np.ndarray, values: np.ndarray, centre: np.ndarray) -> QuadraticModel | None:
    """The quadratic model about ``centre`` fitted to designs U (m, d) of the unit cube and their values (m,).

    Parameters
    ----------
    U : (m, d) ndarray
        Designs (unit cube); m >= (d + 1)(d + 2)/2.
    values : (m,) ndarray
        Their finite objective values.
    centre : (d,) ndarray
        Design the model is expanded about.

    Returns
    -------
    QuadraticModel or None
        None when the designs are fewer than the coefficients or fix no linear model (all on a hyperplane).
    """
    U, values, centre = np.atleast_2d(U), np.asarray(values, float), np.asarray(centre, float)
    m, d = U.shape
    # Centred and scaled to a unit radius: the columns z, z² then have comparable sizes in a small trust region.
    radius = float(np.max(np.abs(U - centre))) or 1.0
    Z = (U - centre) / radius
    shift = float(np.median(values))
    f = values - shift
    A, Q, pairs = _basis(Z)
    if m < A.shape[1] + Q.shape[1] or np.linalg.matrix_rank(A) < A.shape[1]:
        return None
    coef, *_ = np.linalg.lstsq(np.hstack([A, Q]), f, rcond=1e-12)
    linear, curvature = coef[: d + 1], coef[d + 1:]
    H = np.zeros((d, d))
    H[pairs[0], pairs[1]] = curvature
    H = H + np.triu(H, 1).T
    return QuadraticModel(centre, float(linear[0] + shift), linear[1:] / radius, H / radius**2)


def leave_one_out_r2(U: np.ndarray, values: np.ndarray, centre: np.ndarray) -> float:
    """The share of the values' variance the least-squares quadratic predicts for each design left out of its fit:
    1 − PRESS / Σ (f − f̄)², PRESS the sum of the leave-one-out residuals e_i / (1 − h_ii) (Allen 1974).

    Parameters
    ----------
    U : (m, d) ndarray
        Designs (unit cube).
    values : (m,) ndarray
        Their finite values.
    centre : (d,) ndarray
        Design the basis is centred on.

    Returns
    -------
    float
        1 for a quadratic objective, near or below 0 where no quadratic describes the designs; NaN when there are
        not more designs than coefficients (an interpolation predicts nothing left out).
    """
    U, values = np.atleast_2d(U), np.asarray(values, float)
    m, d = U.shape
    if m <= n_coefficients(d):
        return float("nan")
    radius = float(np.max(np.abs(U - centre))) or 1.0
    A, Q, _ = _basis((U - centre) / radius)
    X = np.hstack([A, Q])
    # The hat matrix's diagonal from a thin QR (rank-revealing enough for a basis centred and scaled as here).
    Qr, _ = np.linalg.qr(X)
    h = np.sum(Qr * Qr, axis=1)
    coef, *_ = np.linalg.lstsq(X, values, rcond=1e-12)
    loo = (values - X @ coef) / np.maximum(1.0 - h, 1e-12)
    total = float(np.sum((values - values.mean()) ** 2))
    return 1.0 - float(loo @ loo) / total if total > 0 else float("nan")
