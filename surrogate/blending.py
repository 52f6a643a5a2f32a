"""Degree-graded Chebyshev interpolation on scattered line nodes (paper Eq. 18–19).

Given the l nodes (p_i, q_i) where the sampling lines cross the normal plane, the blend builds an l-dimensional
space of bivariate polynomials ``T_a(p̂) T_b(q̂)`` (Chebyshev polynomials of the first kind on the nodes' bounding
box mapped to [−1, 1]²) graded by total degree, and the Lagrange functions L_i of that space, ``L_i(node_m) = δ_im``.
The paper's coefficient functions of Eq. 18 are then ``a_j^(i)(p, q) = α_j^(i) L_i(p, q)``, which solves the
interpolation conditions of Eq. 19.

The space is chosen like a least-degree interpolant: degree blocks g = 0, 1, 2, ... are taken whole while the
nodes can tell their functions apart; from a block that is only partly needed (or partly resolvable) the
combinations kept are the dominant right singular vectors of the block's Vandermonde columns projected off the span
chosen so far, i.e. the best-conditioned choice.  For l = 7 generic nodes this gives the complete quadratics plus one
cubic combination, the structure of the paper's choice ``m + n <= 2`` plus ``T_2(p)T_1(q) + T_1(p)T_2(q)`` (the
cubic combination itself is data-driven rather than fixed).  Every polynomial of total degree <= the last complete
degree is reproduced exactly.

The construction works in any number m of normal coordinates (m = d − 1); d = 3 gives the bivariate case.
"""

from __future__ import annotations

from itertools import combinations_with_replacement
from typing import Any

import numpy as np

from mechopt.surrogate.errors import SurrogateError

_RANK_TOL = 1e-9


def _degree_block(m: int, g: int) -> list[tuple[int, ...]]:
    """Multi-indices of total degree g in m variables, ordered with the first variable's degree decreasing."""
    out = []
    for combo in combinations_with_replacement(range(m), g):
        alpha = [0] * m
        for v in combo:
            alpha[v] += 1
        out.append(tuple(alpha))
    return out


def _chebyshev_table(x: np.ndarray, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """T_0..T_degree and their derivatives at x, each of shape (degree + 1, n)."""
    T = np.empty((degree + 1, x.size))
    dT = np.empty((degree + 1, x.size))
    T[0], dT[0] = 1.0, 0.0
    if degree >= 1:
        T[1], dT[1] = x, 1.0
    for n in range(1, degree):
        T[n + 1] = 2.0 * x * T[n] - T[n - 1]
        dT[n + 1] = 2.0 * T[n] + 2.0 * x * dT[n] - dT[n - 1]
    return T, dT


class ChebyshevBlend:
    """Lagrange functions of a unisolvent, degree-graded Chebyshev space on scattered nodes.

    Parameters
    ----------
    nodes : (l, m) array
        Node coordinates (caller's units), m >= 1; for the sparse model m = d − 1 = 2 gives (p_i, q_i).
    cond_max : float
        Largest accepted condition number of the interpolation (Vandermonde) matrix.

    Raises
    ------
    SurrogateError
        Repeated nodes, collinear nodes (for l >= 3 in two or more dimensions: the lines would lie in one plane),
        NaN nodes, or an interpolation matrix with condition number above ``cond_max``.
    """

    def __init__(self, nodes: Any, cond_max: float = 1e10) -> None:
        P = np.asarray(nodes, dtype=float)
        if P.ndim == 1:
            P = P[:, None]
        if P.ndim != 2 or P.shape[0] == 0 or P.shape[1] == 0:
            raise SurrogateError(f"nodes must have shape (l, m) with l, m >= 1, got {np.shape(nodes)}")
        if not np.all(np.isfinite(P)):
            raise SurrogateError("line nodes must be finite, got a NaN or infinite coordinate")
        self.nodes = P
        l, m = P.shape
        self._check_geometry(P)
        self.center, self.half_width = self._box(P)
        exps, combo, cond = self._build_space(self.scale(P), cond_max)
        self.exponents = exps  # (n_mono, m) multi-indices of the monomials T_a(p̂)T_b(q̂)...
        self.combinations = combo  # (n_mono, l): columns = basis functions of the space
        self.condition_number = cond
        self._table_degree = int(exps.max())
        V = self._monomials(self.scale(P))[0] @ combo
        # Lagrange functions as monomial coefficients: L(P) = Φ(P) @ W with W = C V^{-1}.
        self.weights = combo @ np.linalg.inv(V)
        self.degree = int(self.exponents.sum(axis=1).max())

    # ------------------------------------------------------------------------------------------ construction
    @staticmethod
    def _check_geometry(P: np.ndarray) -> None:
        l, m = P.shape
        extent = float(np.max(np.ptp(P, axis=0))) if l > 1 else 0.0
        if l > 1:
            diff = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=-1)
            diff[np.diag_indices(l)] = np.inf
            i, j = np.unravel_index(np.argmin(diff), diff.shape)
            if diff[i, j] <= 1e-9 * max(extent, 1e-300) or extent == 0.0:
                raise SurrogateError(
                    f"line nodes {int(min(i, j))} and {int(max(i, j))} coincide at {P[i].tolist()}; "
                    "every line needs its own node"
                )
        if l >= 3 and m >= 2:
            centred = P - P.mean(axis=0)
            sv = np.linalg.svd(centred, compute_uv=False)
            if sv[1] <= 1e-8 * sv[0]:
                raise SurrogateError(
                    f"the {l} line nodes are collinear (spread ratio {sv[1] / sv[0]:.1e}); "
                    "they must span the normal plane for a unisolvent blend"
                )

    @staticmethod
    def _box(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = P.min(axis=0), P.max(axis=0)
        center = 0.5 * (lo + hi)
        half = 0.5 * (hi - lo)
        # A direction the nodes do not spread in (l = 1, or l = 2 in 2-D) borrows the largest half-width.
        fallback = float(half.max()) if half.max() > 0 else 1.0
        half = np.where(half > 1e-12 * fallback, half, fallback)
        return center, half

    def _build_space(self, S: np.ndarray, cond_max: float) -> tuple[np.ndarray, np.ndarray, float]:
        l, m = S.shape
        exps: list[tuple[int, ...]] = []
        columns: list[np.ndarray] = []  # per chosen basis function: (start index in exps, coefficient vector)
        Q = np.zeros((l, 0))
        g = 0
        while Q.shape[1] < l:
            if g > l:
                raise SurrogateError(f"could not find a unisolvent space for the {l} line nodes {S.tolist()}")
            block = _degree_block(m, g)
            start = len(exps)
            exps.extend(block)
            B = self._block_values(S, block)
            R = B - Q @ (Q.T @ B)
            # Scale the test by the block's own size: Chebyshev values are O(1) on the nodes.
            ref = max(np.linalg.norm(B), 1.0)
            _, sv, wh = np.linalg.svd(R, full_matrices=False)
            resolvable = int(np.sum(sv > _RANK_TOL * ref))
            take = min(resolvable, l - Q.shape[1])
            if take == len(block):
                chosen = np.eye(len(block))
            else:
                chosen = wh[:take].T
            for c in chosen.T:
                columns.append((start, c))
            if take:
                newQ, _ = np.linalg.qr(np.hstack([Q, B @ chosen]))
                Q = newQ[:, : Q.shape[1] + take]
            g += 1
        combo = np.zeros((len(exps), l))
        for col, (start, c) in enumerate(columns):
            combo[start : start + c.size, col] = c
        V = self._monomials_from(S, np.array(exps), self._max_degree(exps))[0] @ combo
        cond = float(np.linalg.cond(V))
        if not np.isfinite(cond) or cond > cond_max:
            raise SurrogateError(
                f"the blend's interpolation matrix has condition number {cond:.2e} > {cond_max:.0e}; "
                "spread the line nodes over the normal plane"
            )
        return np.array(exps, dtype=np.int64).reshape(-1, m), combo, cond

    @staticmethod
    def _max_degree(exps: list[tuple[int, ...]]) -> int:
        return int(max(max(e) for e in exps)) if exps else 0

    @staticmethod
    def _block_values(S: np.ndarray, block: list[tuple[int, ...]]) -> np.ndarray:
        deg = max(max(e) for e in block)
        tables = [_chebyshev_table(S[:, v], deg)[0] for v in range(S.shape[1])]
        out = np.ones((S.shape[0], len(block)))
        for c, alpha in enumerate(block):
            for v, a in enumerate(alpha):
                out[:, c] *= tables[v][a]
        return out

    @staticmethod
    def _monomials_from(S: np.ndarray, exps: np.ndarray, deg: int) -> tuple[np.ndarray, np.ndarray]:
        n, m = S.shape
        tables = [_chebyshev_table(S[:, v], deg) for v in range(m)]
        phi = np.ones((n, exps.shape[0]))
        dphi = np.ones((m, n, exps.shape[0]))
        for c, alpha in enumerate(exps):
            for v, a in enumerate(alpha):
                T, dT = tables[v]
                phi[:, c] *= T[a]
                for w in range(m):
                    dphi[w, :, c] *= dT[a] if w == v else T[a]
        return phi, dphi

    def _monomials(self, S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self._monomials_from(S, self.exponents, self._table_degree)

    # ------------------------------------------------------------------------------------------- evaluation
    @property
    def n_nodes(self) -> int:
        """Number of nodes l (= dimension of the interpolation space)."""
        return int(self.nodes.shape[0])

    def scale(self, P: Any) -> np.ndarray:
        """Map coordinates (caller's units) to the nodes' bounding box scaled to [−1, 1]^m, shape (n, m)."""
        P = np.asarray(P, dtype=float)
        if P.ndim == 1:
            P = P[:, None] if self.nodes.shape[1] == 1 else P[None, :]
        return (P - self.center) / self.half_width

    def basis(self, P: Any) -> np.ndarray:
        """Values of the l basis functions of the interpolation space at P, shape (n, l)."""
        return self._monomials(self.scale(P))[0] @ self.combinations

    def lagrange(self, P: Any) -> np.ndarray:
        """Lagrange functions L_i at P (caller's units), shape (n, l); ``L_i(node_m) = δ_im``."""
        return self._monomials(self.scale(P))[0] @ self.weights

    def lagrange_gradient(self, P: Any) -> np.ndarray:
        """Gradients ∂L_i/∂P_v at P, shape (n, l, m) (per caller's unit)."""
        _, dphi = self._monomials(self.scale(P))
        grads = np.einsum("vnc,ci->niv", dphi, self.weights)
        return grads / self.half_width[None, None, :]

    def interpolate(self, values: Any) -> np.ndarray:
        """Monomial coefficients of the interpolant of ``values`` (l,) at the nodes, shape (n_mono,)."""
        return self.weights @ np.asarray(values, dtype=float)

    # ------------------------------------------------------------------------------------------------ JSON
    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly representation, including the chosen space so a reload does not depend on LAPACK."""
        return {
            "nodes": self.nodes.tolist(),
            "exponents": self.exponents.tolist(),
            "combinations": self.combinations.tolist(),
            "condition_number": self.condition_number,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ChebyshevBlend:
        """Inverse of :meth:`to_dict` (rebuilds the space from the nodes when it was not stored)."""
        if "nodes" not in data:
            raise SurrogateError("blend dictionary lacks the key 'nodes'")
        blend = cls(data["nodes"])
        if "exponents" in data and "combinations" in data:
            exps = np.asarray(data["exponents"], dtype=np.int64).reshape(-1, blend.nodes.shape[1])
            combo = np.asarray(data["combinations"], dtype=float)
            if combo.shape != (exps.shape[0], blend.n_nodes):
                raise SurrogateError(
                    f"blend combinations must have shape ({exps.shape[0]}, {blend.n_nodes}), got {combo.shape}"
                )
            blend.exponents, blend.combinations = exps, combo
            blend._table_degree = int(exps.max())
            blend.degree = int(exps.sum(axis=1).max())
            V = blend._monomials(blend.scale(blend.nodes))[0] @ combo
            blend.weights = combo @ np.linalg.inv(V)
            blend.condition_number = float(np.linalg.cond(V))
        return blend
