"""Euler-Bernoulli beam elements of the connecting rod: bending matrices of a pinned-pinned rod.

Each node carries the transverse displacement w and the rotation w'; cubic Hermite shape functions (the paper's
φ2, φ3, φ5, φ6).  The ends A and B are pinned (w = 0), so the free coordinates are w'_0, (w_i, w'_i) for the inner
nodes and w'_n.  Besides the mass and stiffness matrices the module returns what the inertial loading and the axial
force need, all for loads polynomial in the arc length s from A:

* ``load[p]`` = ∫ s^p N(s)ᵀ ds (p = 0, 1): a transverse load q(s) = q0 + q1 s gives the force vector
  q0 load[0] + q1 load[1];
* ``geo[p]`` = ∫ s^p N'(s)ᵀ N'(s) ds (p = 0, 1, 2): an axial tension T(s) = c0 + c1 s + c2 s² gives the geometric
  stiffness Σ c_p geo[p].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["RodMatrices", "hermite", "rod_matrices"]

# 4-point Gauss-Legendre on [0, 1]: exact for the degree-6 integrands of geo[2]
_GX, _GW = np.polynomial.legendre.leggauss(4)
_GX = 0.5 * (_GX + 1.0)
_GW = 0.5 * _GW


def hermite(xi: np.ndarray, le: float) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Hermite shape functions of one element and their s-derivatives.

    Parameters
    ----------
    xi : ndarray
        Local coordinates in [0, 1].
    le : float
        Element length (m).

    Returns
    -------
    N, dN : ndarray of shape (len(xi), 4)
        Values and d/ds of the functions of (w_left, w'_left, w_right, w'_right).
    """
    xi = np.asarray(xi, dtype=float)
    N = np.stack([1 - 3 * xi**2 + 2 * xi**3, le * (xi - 2 * xi**2 + xi**3),
                  3 * xi**2 - 2 * xi**3, le * (-xi**2 + xi**3)], axis=-1)
    dN = np.stack([(-6 * xi + 6 * xi**2) / le, 1 - 4 * xi + 3 * xi**2,
                   (6 * xi - 6 * xi**2) / le, -2 * xi + 3 * xi**2], axis=-1)
    return N, dN


@dataclass(frozen=True)
class RodMatrices:
    """Bending matrices of the pinned-pinned rod over its free coordinates (see the module docstring).

    Attributes
    ----------
    M, K : ndarray (m, m)
        Consistent mass (kg, per unit ρA already included) and stiffness (N/m, EI included) matrices.
    load : ndarray (2, m)
        ∫ s^p Nᵀ ds (m^(1+p)); multiply by the load per length coefficients.
    geo : ndarray (3, m, m)
        ∫ s^p N'ᵀ N' ds (m^(p-1)); multiply by the tension coefficients (N/m^p).
    free : ndarray of int
        Indices of the free coordinates among the 2(n+1) nodal ones.
    n_elements : int
        Number of elements.
    length : float
        Rod length (m).
    """

    M: np.ndarray
    K: np.ndarray
    load: np.ndarray
    geo: np.ndarray
    free: np.ndarray
    n_elements: int
    length: float

    def shape_at(self, s: np.ndarray) -> np.ndarray:
        """Matrix mapping the free coordinates to w at the arc lengths ``s`` (m), shape (len(s), m)."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        le = self.length / self.n_elements
        el = np.clip((s / le).astype(int), 0, self.n_elements - 1)
        N, _ = hermite(s / le - el, le)
        full = np.zeros((len(s), 2 * (self.n_elements + 1)))
        for j in range(4):
            full[np.arange(len(s)), 2 * el + j] = N[:, j]
        return full[:, self.free]


def rod_matrices(length: float, n_elements: int, mass_per_length: float, bending_stiffness: float) -> RodMatrices:
    """Assemble the pinned-pinned rod's bending matrices.

    Parameters
    ----------
    length : float
        Rod length (m).
    n_elements : int
        Number of equal elements (>= 2).
    mass_per_length : float
        ρA (kg/m).
    bending_stiffness : float
        EI (N m²).

    Returns
    -------
    RodMatrices
    """
    n = int(n_elements)
    le = length / n
    ndof = 2 * (n + 1)
    N, dN = hermite(_GX, le)
    # Hermite cubics integrate the element mass/stiffness exactly with 4 Gauss points too
    dd = np.stack([(-6 + 12 * _GX) / le**2, (-4 + 6 * _GX) / le,
                   (6 - 12 * _GX) / le**2, (-2 + 6 * _GX) / le], axis=-1)
    M = np.zeros((ndof, ndof))
    K = np.zeros((ndof, ndof))
    load = np.zeros((2, ndof))
    geo = np.zeros((3, ndof, ndof))
    for e in range(n):
        idx = slice(2 * e, 2 * e + 4)
        s = (e + _GX) * le
        w = _GW * le
        M[idx, idx] += mass_per_length * np.einsum("g,gi,gj->ij", w, N, N)
        K[idx, idx] += bending_stiffness * np.einsum("g,gi,gj->ij", w, dd, dd)
        for p in range(2):
            load[p, idx] += np.einsum("g,gi->i", w * s**p, N)
        for p in range(3):
            geo[p, idx, idx] += np.einsum("g,gi,gj->ij", w * s**p, dN, dN)
    free = np.array([i for i in range(ndof) if i not in (0, ndof - 2)])
    return RodMatrices(M=M[np.ix_(free, free)], K=K[np.ix_(free, free)], load=load[:, free],
                       geo=geo[:, free][:, :, free], free=free, n_elements=n, length=float(length))
