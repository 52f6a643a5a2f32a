"""One-dimensional exponential fitting: ``T_k ≈ Σ_j β_j z_j^k`` from equispaced samples (paper Eq. 9).

Two subspace methods are offered, both on the overdetermined Hankel matrix ``H[r, c] = T_{r+c}`` and both with a
least-squares (``"ls"``) or total-least-squares (``"tls"``) solution of the shift-invariance equation:

* ``"matrix_pencil"`` (Hua & Sarkar): the pencil of the dominant *right* singular vectors of H;
* ``"esprit"`` (Roy & Kailath): the shift invariance of the dominant *left* singular vectors of H.

The coefficients β then follow from a linear least-squares fit of the samples on the Vandermonde basis z_j^k.
Real data give real nodes and complex-conjugate pairs; the pair's coefficients are made exactly conjugate so the
model is real.  A fit is evaluated at any real k as ``Re Σ β_j exp(k Log z_j)`` with the principal logarithm.

Automatic order
---------------
All orders n = 1 .. n_max are fitted from one SVD, with n_max <= (N − 2)/3 and at most the numerical rank of H.
For each, the relative noise level is estimated with the degrees of freedom taken into account:

    σ̂(n) = ‖(fit − T) / |T|‖ / sqrt(N − 3n),        |T_k| floored at 1 % of max |T|.

Residuals are relative because simulation noise is relative (plain residuals let spare terms chase the noise where
|T| is largest).  A term costs a node and a coefficient; one more degree of freedom per term accounts for the nodes
being *selected* to fit the data (with 2 per term the estimate kept drifting down past the true order on noisy
smooth curves, and over-fitted orders won).  The order chosen is the smallest *admissible* n whose σ̂(n) is within
25 % of the best admissible one, plus a floor of 1e-12 so exact data stop at the true order.  On smooth curves with
1e-4 relative noise this gives fits whose error between the samples is of the order of the noise.

An order is admissible when

* it has no negative real node: such a node is an oscillation at the Nyquist frequency that smooth data cannot
  contain (it fits noise) and that has no real continuation between integer k;
* its terms do not cancel catastrophically: ``max_k Σ |β_j||z_j|^k`` is at most 1e3 times ``max |T|``.

Negative real nodes
-------------------
They are rejected by the automatic order.  When the caller forces an ``order`` that produces one, the fit keeps it,
warns (:class:`~surrogate.errors.SurrogateWarning`) and says so in ``message``; the real part of the principal-log
continuation ``β |z|^k cos(π k)`` still interpolates the integer samples.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mechopt.surrogate.errors import SurrogateError, SurrogateWarning

METHODS = ("matrix_pencil", "esprit")
SOLVERS = ("ls", "tls")

_CANCELLATION_LIMIT = 1e3
_ORDER_TOLERANCE = 0.25
_EXACT_FLOOR = 1e-12
_RANK_TOL = 1e-13
_DOF_PER_TERM = 3
_WEIGHT_FLOOR = 1e-2


@dataclass(frozen=True, eq=False)
class ExponentialFit:
    """Result of :func:`fit_exponential`: the model ``T(k) = Re Σ_j β_j exp(k Log z_j)``.

    Attributes
    ----------
    nodes : (n,) complex array
        z_j = exp(λ_j), the growth factor per sample step.
    coefficients : (n,) complex array
        β_j, the value of term j at k = 0 (data units).
    order : int
        Number of terms n.
    rms_residual : float
        Root-mean-square of the residual at the fitted samples (data units).
    method : str
        ``"<method>/<solver>"``, e.g. ``"matrix_pencil/ls"``.
    message : str
        How the order was chosen and any caveat.
    n_samples : int
        Number of samples fitted.
    singular_values : (m,) array
        Singular values of the Hankel matrix divided by the largest (the order diagnostics).
    order_scores : dict
        ``{n: σ̂(n)}``, the relative noise estimate of every order tried (empty when the order was forced).
    """

    nodes: np.ndarray
    coefficients: np.ndarray
    order: int
    rms_residual: float
    method: str
    message: str
    n_samples: int
    singular_values: np.ndarray = field(default_factory=lambda: np.zeros(0))
    order_scores: dict[int, float] = field(default_factory=dict)

    @property
    def exponents(self) -> np.ndarray:
        """λ_j = Log z_j (principal branch), per sample step, shape (n,) complex."""
        return _log_nodes(self.nodes)

    @property
    def has_negative_nodes(self) -> bool:
        """Whether a node is (numerically) a negative real number."""
        return bool(np.any(_negative_real(self.nodes)))

    def __call__(self, k: Any) -> np.ndarray:
        """Evaluate the fit at real sample positions ``k`` (any shape); returns a real array of the same shape."""
        k = np.asarray(k, dtype=float)
        if self.order == 0:
            return np.zeros(k.shape)
        flat = k.reshape(-1)
        vals = np.exp(np.multiply.outer(flat, self.exponents)) @ self.coefficients
        return vals.real.reshape(k.shape)

    def derivative(self, k: Any) -> np.ndarray:
        """dT/dk at real ``k`` (data units per sample step), same shape as ``k``."""
        k = np.asarray(k, dtype=float)
        if self.order == 0:
            return np.zeros(k.shape)
        lam = self.exponents
        vals = np.exp(np.multiply.outer(k.reshape(-1), lam)) @ (self.coefficients * lam)
        return vals.real.reshape(k.shape)

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly representation; complex numbers are ``[re, im]`` pairs."""
        return {
            "nodes": [[float(z.real), float(z.imag)] for z in self.nodes],
            "coefficients": [[float(b.real), float(b.imag)] for b in self.coefficients],
            "order": self.order,
            "rms_residual": self.rms_residual,
            "method": self.method,
            "message": self.message,
            "n_samples": self.n_samples,
            "singular_values": self.singular_values.tolist(),
            "order_scores": {str(n): s for n, s in self.order_scores.items()},
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ExponentialFit:
        """Inverse of :meth:`to_dict`."""
        try:
            nodes = np.array([complex(re, im) for re, im in data["nodes"]], dtype=complex)
            coefs = np.array([complex(re, im) for re, im in data["coefficients"]], dtype=complex)
            return cls(
                nodes=nodes,
                coefficients=coefs,
                order=int(data["order"]),
                rms_residual=float(data["rms_residual"]),
                method=str(data["method"]),
                message=str(data["message"]),
                n_samples=int(data["n_samples"]),
                singular_values=np.asarray(data.get("singular_values", []), dtype=float),
                order_scores={int(n): float(s) for n, s in data.get("order_scores", {}).items()},
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise SurrogateError(f"malformed exponential fit dictionary: {exc}") from exc


def _log_nodes(nodes: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return np.log(np.asarray(nodes, dtype=complex))


def _negative_real(nodes: np.ndarray) -> np.ndarray:
    z = np.asarray(nodes, dtype=complex)
    return (z.real < 0) & (np.abs(z.imag) <= 1e-12 * np.abs(z))


def _hankel(y: np.ndarray, L: int) -> np.ndarray:
    idx = np.arange(y.size - L)[:, None] + np.arange(L + 1)[None, :]
    return y[idx]


def _pencil_parameter(n_samples: int, method: str, n_max: int) -> int:
    """Window L of the Hankel matrix (N − L) × (L + 1) able to carry n_max terms."""
    if method == "matrix_pencil":
        # Hua & Sarkar: L near N/2 averages the noise best; the right singular vectors need L >= n.
        return min(max(n_samples // 2, n_max), n_samples - n_max)
    # ESPRIT on the left singular vectors: the same near-square window (tall matrices were found less accurate
    # on noisy smooth curves); it needs L + 1 >= n and N − L − 1 >= n.
    return min(max(n_samples // 2, n_max - 1), n_samples - n_max - 1)


def _shift_nodes(basis: np.ndarray, n: int, solver: str) -> np.ndarray:
    """Eigenvalues of the shift operator on the n-dimensional signal subspace spanned by ``basis[:, :n]``."""
    S = basis[:, :n]
    S1, S2 = S[:-1], S[1:]
    if solver == "ls":
        phi = np.linalg.lstsq(S1, S2, rcond=None)[0]
    else:
        _, _, wh = np.linalg.svd(np.hstack([S1, S2]))
        W = wh.conj().T
        phi = -W[:n, n:] @ np.linalg.inv(W[n:, n:])
    z = np.linalg.eigvals(phi)
    # A real pencil gives exact conjugate pairs; clean round-off imaginary parts of real nodes.
    z = np.where(np.abs(z.imag) <= 1e-13 * np.abs(z), z.real + 0j, z)
    return z


def _coefficients(y: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    k = np.arange(y.size)
    logz = _log_nodes(nodes)
    # Each column is divided by its largest magnitude (in log space, so |z|^k cannot overflow) and then by its
    # norm: fast-decaying and growing terms are solved on an equal footing.
    shift = np.maximum(0.0, (y.size - 1) * logz.real)
    V = np.exp(np.multiply.outer(k, logz) - shift)
    norms = np.linalg.norm(V, axis=0)
    norms[~(norms > 0)] = 1.0
    c = np.linalg.lstsq(V / norms, y.astype(complex), rcond=None)[0]
    with np.errstate(under="ignore"):
        beta = c / norms * np.exp(-shift)
    return _conjugate_symmetric(nodes, beta)


def _conjugate_symmetric(nodes: np.ndarray, beta: np.ndarray) -> np.ndarray:
    beta = beta.copy()
    real = np.abs(nodes.imag) == 0
    beta[real] = beta[real].real
    used = np.zeros(nodes.size, dtype=bool)
    for j in np.flatnonzero(~real):
        if used[j]:
            continue
        others = np.flatnonzero(~used & ~real)
        others = others[others != j]
        if others.size == 0:
            continue
        partner = others[np.argmin(np.abs(nodes[others] - np.conj(nodes[j])))]
        mean = 0.5 * (beta[j] + np.conj(beta[partner]))
        beta[j], beta[partner] = mean, np.conj(mean)
        used[j] = used[partner] = True
    return beta


def _evaluate_at_samples(nodes: np.ndarray, beta: np.ndarray, n_samples: int) -> np.ndarray:
    k = np.arange(n_samples)
    with np.errstate(over="ignore", invalid="ignore"):
        return (np.exp(np.multiply.outer(k, _log_nodes(nodes))) @ beta).real


def _cancellation(nodes: np.ndarray, beta: np.ndarray, n_samples: int, scale: float) -> float:
    k = np.arange(n_samples)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        mags = np.exp(np.multiply.outer(k, np.log(np.abs(nodes))))
        worst = float(np.max(mags @ np.abs(beta)) / scale)
    return worst if np.isfinite(worst) else np.inf


def _check_samples(values: Any) -> np.ndarray:
    y = np.asarray(values, dtype=float)
    if y.ndim != 1:
        raise SurrogateError(f"samples must be a 1-D sequence, got shape {y.shape}")
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise SurrogateError(f"sample {int(bad[0])} is {y[bad[0]]}; all samples must be finite")
    if y.size < 2:
        raise SurrogateError(f"need at least 2 samples for an exponential fit, got {y.size}")
    return y


def _check_arguments(values: Any, order: int | None, method: str, solver: str, max_order: int) -> np.ndarray:
    """The samples as a float array, after checking every argument of :func:`fit_exponential`."""
    if method not in METHODS:
        raise SurrogateError(f"method must be one of {METHODS}, got {method!r}")
    if solver not in SOLVERS:
        raise SurrogateError(f"solver must be one of {SOLVERS}, got {solver!r}")
    y = _check_samples(values)
    if order is not None:
        if isinstance(order, bool) or int(order) != order or order < 1:
            raise SurrogateError(f"order must be a positive integer, got {order!r}")
        if y.size < 2 * int(order):
            raise SurrogateError(
                f"order n = {int(order)} needs at least 2n = {2 * int(order)} samples, got N = {y.size}"
            )
    if int(max_order) < 1:
        raise SurrogateError(f"max_order must be >= 1, got {max_order!r}")
    return y


@dataclass(frozen=True, eq=False)
class _SignalSubspace:
    """What the fits of every order share: the samples, the SVD of their Hankel matrix and the residual weights.

    Attributes
    ----------
    samples : (N,) array
        T_0 .. T_{N−1} (data units).
    scale : float
        max |T_k| (data units).
    basis : 2-D array
        Singular vectors spanning the signal subspace (right ones for the matrix pencil, left ones for ESPRIT).
    singular_values : (m,) array
        Singular values of the Hankel matrix divided by the largest.
    solver : str
        ``"ls"`` or ``"tls"``.
    weights : (N,) array
        1 / max(|T_k|, 1 % of max |T|) (per data unit): they make the order criterion's residuals relative.
    """

    samples: np.ndarray
    scale: float
    basis: np.ndarray
    singular_values: np.ndarray
    solver: str
    weights: np.ndarray

    @classmethod
    def of(cls, y: np.ndarray, scale: float, method: str, solver: str, n_max: int) -> _SignalSubspace:
        """The subspace of samples ``y`` (max |y| = ``scale`` > 0) able to carry ``n_max`` terms."""
        H = _hankel(y / scale, _pencil_parameter(y.size, method, n_max))
        U, s, Vh = np.linalg.svd(H, full_matrices=False)
        # Simulation noise is relative, and unweighted residuals let spare terms chase the noise where |T| is largest.
        weights = 1.0 / np.maximum(np.abs(y), _WEIGHT_FLOOR * scale)
        return cls(y, scale, Vh.T if method == "matrix_pencil" else U, s / s[0], solver, weights)

    def fit_order(self, n: int) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Nodes, coefficients, rms residual (data units) and relative rms residual of order n."""
        try:
            z = _shift_nodes(self.basis, n, self.solver)
        except np.linalg.LinAlgError:
            z = np.full(n, np.nan + 0j)
        if not np.all(np.isfinite(z)) or np.any(z == 0):
            return z, np.full(n, np.nan + 0j), np.inf, np.inf
        y = self.samples
        beta = _coefficients(y, z)
        resid = _evaluate_at_samples(z, beta, y.size) - y
        rms = float(np.sqrt(np.mean(resid**2)))
        rel = float(np.sqrt(np.mean((resid * self.weights) ** 2)))
        if not (np.isfinite(rms) and np.isfinite(rel)):
            return z, beta, np.inf, np.inf
        return z, beta, rms, rel


def _fit_given_order(sub: _SignalSubspace, order: int, label: str) -> tuple[ExponentialFit, str | None]:
    """The fit of the caller's order, and the warning it deserves (None when it needs none)."""
    z, beta, rms, _ = sub.fit_order(order)
    if not np.isfinite(rms):
        raise SurrogateError(
            f"order n = {order} gives a degenerate {label} fit (zero or infinite node); try a smaller order"
        )
    message = f"order {order} given by the caller"
    warning = None
    if np.any(_negative_real(z)):
        note = "negative real node(s): evaluated as β|z|^k cos(πk) between integers (Nyquist oscillation)"
        warning = f"exponential fit of order {order}: {note}"
        message += f"; {note}"
    fit = ExponentialFit(z, beta, order, rms, label, message, sub.samples.size, sub.singular_values)
    return fit, warning


def _fit_automatic_order(sub: _SignalSubspace, max_order: int, label: str) -> tuple[ExponentialFit, str | None]:
    """The fit of the order chosen as the module docstring says, and the warning it deserves (None: none)."""
    N = sub.samples.size
    rank = int(np.sum(sub.singular_values > _RANK_TOL))
    n_max = max(1, min(max_order, (N - 2) // _DOF_PER_TERM, rank, sub.basis.shape[0] - 1, sub.basis.shape[1]))
    candidates: dict[int, tuple[np.ndarray, np.ndarray, float]] = {}
    scores: dict[int, float] = {}
    admissible: dict[int, bool] = {}
    for n in range(1, n_max + 1):
        z, beta, rms, rel = sub.fit_order(n)
        candidates[n] = (z, beta, rms)
        scores[n] = rel * np.sqrt(N / max(N - _DOF_PER_TERM * n, 1))
        admissible[n] = bool(
            np.isfinite(rms)
            and not np.any(_negative_real(z))
            and np.all(np.isfinite(beta))
            and _cancellation(z, beta, N, sub.scale) <= _CANCELLATION_LIMIT
        )
    pool = [n for n in scores if admissible[n]]
    caveat = ""
    if not pool:
        pool = list(scores)
        caveat = "; no order free of negative real nodes or cancellation, kept the best anyway"
    best = min(scores[n] for n in pool)
    threshold = (1.0 + _ORDER_TOLERANCE) * best + _EXACT_FLOOR
    chosen = min(n for n in pool if scores[n] <= threshold)
    z, beta, rms = candidates[chosen]
    message = (
        f"automatic order {chosen} of 1..{n_max}: relative noise estimate {scores[chosen]:.3g} "
        f"(best {best:.3g}){caveat}"
    )
    warning = f"exponential fit: {message}" if caveat and np.any(_negative_real(z)) else None
    return ExponentialFit(z, beta, chosen, rms, label, message, N, sub.singular_values, scores), warning


def fit_exponential(
    values: Any,
    order: int | None = None,
    method: str = "matrix_pencil",
    solver: str = "ls",
    max_order: int = 10,
) -> ExponentialFit:
    """Fit ``T_k ≈ Σ_j β_j z_j^k`` to equispaced samples ``T_0 .. T_{N−1}``.

    Parameters
    ----------
    values : (N,) array
        Real samples at k = 0, 1, ..., N − 1 (data units, e.g. N·m for a torque).
    order : int, optional
        Number of terms n; needs N >= 2n.  ``None`` chooses it automatically (see the module docstring).
    method : {"matrix_pencil", "esprit"}
        Subspace method.
    solver : {"ls", "tls"}
        Least squares or total least squares for the shift-invariance equation.
    max_order : int
        Largest order tried by the automatic choice.

    Returns
    -------
    ExponentialFit

    Raises
    ------
    SurrogateError
        NaN/inf samples, fewer than 2 samples, fewer than 2n samples for a forced order n, unknown method/solver.
    """
    y = _check_arguments(values, order, method, solver, max_order)
    N = y.size
    label = f"{method}/{solver}"
    scale = float(np.max(np.abs(y)))
    if scale == 0.0:
        return ExponentialFit(
            nodes=np.zeros(0, dtype=complex),
            coefficients=np.zeros(0, dtype=complex),
            order=0,
            rms_residual=0.0,
            method=label,
            message="all samples are zero: empty model",
            n_samples=N,
        )
    if order is not None:
        sub = _SignalSubspace.of(y, scale, method, solver, int(order))
        fit, warning = _fit_given_order(sub, int(order), label)
    else:
        sub = _SignalSubspace.of(y, scale, method, solver, max(1, min(int(max_order), (N - 2) // _DOF_PER_TERM)))
        fit, warning = _fit_automatic_order(sub, int(max_order), label)
    if warning is not None:
        # Issued here, not in the helpers, so that it points at the caller of fit_exponential.
        warnings.warn(warning, SurrogateWarning, stacklevel=2)
    return fit
