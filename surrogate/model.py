"""The blended sparse exponential model (paper Eq. 13–19, Algorithm 1).

With the plan's coordinates (P, d) of a point X (see :mod:`surrogate.lines`), the model is

    T(X) = Σ_i L_i(P) f_i(d),        f_i(d) = Σ_j α_j^(i) exp(λ_j^(i) d),

where f_i is line i's exponential fit and L_i the Lagrange functions of the Chebyshev blend on the line nodes.  This
is the paper's Eq. 17 with ``a_j^(i)(p, q) = α_j^(i) L_i(p, q)`` (Eq. 18–19).  Line i is sampled at d = k + d(δ(i))
for k = k0 .. k0 + N_i − 1 and its fit is made in the local index j = k − k0, so

    f_i(d) = fit_i(d − s_i),        s_i = k0 + d(δ(i)),        α_j^(i) = β_j^(i) exp(−s_i λ_j^(i))   (Eq. 15).

Because L_i(node_m) = δ_im, the model restricted to line i is exactly that line's 1-D fit, so it reproduces the
samples as well as the fit does.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.surrogate.blending import ChebyshevBlend
from mechopt.surrogate.errors import SurrogateError, SurrogateWarning
from mechopt.surrogate.exponential_fit import METHODS, SOLVERS, ExponentialFit, fit_exponential
from mechopt.surrogate.lines import LineHull, LinePlan
from mechopt.surrogate.model_file import model_from_dict, model_to_dict, read_model, write_model


def _check_line(i: int, sample: Any) -> tuple[np.ndarray, np.ndarray]:
    try:
        ks, values = sample
    except (TypeError, ValueError) as exc:
        raise SurrogateError(f"line {i}: samples must be a pair (ks, values), got {type(sample).__name__}") from exc
    ks = np.asarray(ks, dtype=float).reshape(-1)
    values = np.asarray(values, dtype=float).reshape(-1)
    if ks.size != values.size:
        raise SurrogateError(f"line {i}: {ks.size} indices but {values.size} values")
    if ks.size == 0:
        raise SurrogateError(f"line {i}: no samples")
    if not np.all(np.isfinite(ks)) or np.any(ks != np.round(ks)):
        raise SurrogateError(f"line {i}: sample indices k must be integers, got {ks[:5].tolist()}...")
    order = np.argsort(ks, kind="stable")
    ks, values = ks[order].astype(np.int64), values[order]
    gaps = np.flatnonzero(np.diff(ks) != 1)
    if gaps.size:
        g = int(gaps[0])
        raise SurrogateError(
            f"line {i}: sample indices must be consecutive integers, found a jump from k = {ks[g]} to {ks[g + 1]}"
        )
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise SurrogateError(f"line {i}: sample at k = {int(ks[bad[0]])} is {values[bad[0]]}; samples must be finite")
    return ks, values


class SparseExponentialModel:
    """Blended sparse exponential surrogate ``T(X) = Σ_i L_i(p, q) f_i(d)`` (paper Eq. 17).

    Options are given here; data are given to :meth:`fit` (scipy / SMT style).

    Parameters
    ----------
    order : int or sequence of int, optional
        Number of exponential terms per line (one value for all lines or one per line); ``None`` chooses each
        line's order automatically (see :func:`surrogate.exponential_fit.fit_exponential`).
    method : {"matrix_pencil", "esprit"}
        1-D exponential fitting method.
    solver : {"ls", "tls"}
        Least or total least squares in the fitting method.
    max_order : int
        Largest order tried by the automatic choice.
    cond_max : float
        Largest accepted condition number of the blend's interpolation matrix.

    Attributes (after fit)
    ----------------------
    plan : LinePlan
        The lines, with ``k_ranges`` set to the fitted sample ranges.
    fits : list of ExponentialFit
        Per-line fits in the local index j = k − k0.
    shifts : (l,) array
        s_i = k0 + d(δ(i)), so f_i(d) = fits[i](d − s_i).
    blend : ChebyshevBlend
        Lagrange functions on the line nodes.
    """

    def __init__(
        self,
        order: int | Sequence[int] | None = None,
        method: str = "matrix_pencil",
        solver: str = "ls",
        max_order: int = 10,
        cond_max: float = 1e10,
        extrapolation: str = "linear",
    ) -> None:
        if extrapolation not in ("linear", "exponential"):
            raise SurrogateError(f"extrapolation must be 'linear' or 'exponential', got {extrapolation!r}")
        if method not in METHODS:
            raise SurrogateError(f"method must be one of {METHODS}, got {method!r}")
        if solver not in SOLVERS:
            raise SurrogateError(f"solver must be one of {SOLVERS}, got {solver!r}")
        self.order = order
        self.method = method
        self.solver = solver
        self.max_order = int(max_order)
        self.cond_max = float(cond_max)
        self.extrapolation = extrapolation
        self.plan: LinePlan | None = None
        self.fits: list[ExponentialFit] = []
        self.shifts = np.zeros(0)
        self.blend: ChebyshevBlend | None = None
        self._hull: LineHull | None = None

    def __repr__(self) -> str:
        state = f"l={self.l}, orders={self.orders}" if self.plan is not None else "unfitted"
        return f"SparseExponentialModel(method={self.method!r}, solver={self.solver!r}, {state})"

    # -------------------------------------------------------------------------------------------------- fit
    def _orders_for(self, l: int) -> list[int | None]:
        if self.order is None:
            return [None] * l
        if np.ndim(self.order) == 0:
            return [int(self.order)] * l  # type: ignore[arg-type]
        orders = list(self.order)  # type: ignore[arg-type]
        if len(orders) != l:
            raise SurrogateError(f"order must give one value per line ({l}), got {len(orders)}")
        return [None if o is None else int(o) for o in orders]

    def fit(self, plan: LinePlan, line_samples: Sequence[tuple[Any, Any]]) -> SparseExponentialModel:
        """Fit the per-line exponential models and blend them.

        Parameters
        ----------
        plan : LinePlan
            The sampling lines (its ``k_ranges`` are replaced by the ranges of the samples given).
        line_samples : sequence of (ks, values)
            For each line i, consecutive integer indices k and the sampled values ``T(plan.point(i, k))``
            (data units).

        Returns
        -------
        SparseExponentialModel
            ``self``, fitted.

        Raises
        ------
        SurrogateError
            Wrong number of lines, non-consecutive indices, NaN values, too few samples for the order, or line
            nodes that admit no unisolvent blend.
        """
        if not isinstance(plan, LinePlan):
            raise SurrogateError(f"plan must be a LinePlan, got {type(plan).__name__}")
        if len(line_samples) != plan.n_lines:
            raise SurrogateError(f"the plan has {plan.n_lines} lines but {len(line_samples)} sample sets were given")
        checked = [_check_line(i, s) for i, s in enumerate(line_samples)]
        blend = ChebyshevBlend(plan.line_nodes(), cond_max=self.cond_max)
        fits = []
        for i, ((_, values), order) in enumerate(zip(checked, self._orders_for(plan.n_lines), strict=True)):
            try:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always", SurrogateWarning)
                    fits.append(
                        fit_exponential(
                            values, order=order, method=self.method, solver=self.solver, max_order=self.max_order
                        )
                    )
            except SurrogateError as exc:
                raise SurrogateError(f"line {i}: {exc}") from exc
            for w in caught:
                # Re-issue with the line number, which the 1-D fit cannot know.
                warnings.warn(f"line {i}: {w.message}", w.category, stacklevel=2)
        k_ranges = np.array([[ks[0], ks[-1]] for ks, _ in checked], dtype=np.int64)
        self.plan = plan.with_k_ranges(k_ranges)
        self.fits = fits
        self.shifts = k_ranges[:, 0] + plan.line_shifts()
        self.blend = blend
        self._hull = None
        return self

    def _require_fit(self) -> None:
        if self.plan is None or self.blend is None:
            raise SurrogateError("the model is not fitted yet; call fit(plan, line_samples) first")

    # ------------------------------------------------------------------------------------------- inspection
    @property
    def l(self) -> int:  # noqa: E743 - the paper's symbol for the number of lines
        """Number of lines l."""
        return 0 if self.plan is None else self.plan.n_lines

    @property
    def orders(self) -> list[int]:
        """Number of terms n_i of every line."""
        return [f.order for f in self.fits]

    @property
    def exponents(self) -> list[np.ndarray]:
        """λ_j^(i) = <φ_j^(i), Δ> per line, per unit of d (one sample step), complex arrays."""
        return [f.exponents for f in self.fits]

    @property
    def coefficients(self) -> list[np.ndarray]:
        """α_j^(i) of Eq. 15 per line: f_i(d) = Re Σ_j α_j^(i) exp(λ_j^(i) d), complex arrays (data units)."""
        return [f.coefficients * np.exp(-s * f.exponents) for f, s in zip(self.fits, self.shifts, strict=True)]

    @property
    def n_terms(self) -> int:
        """Total number of exponential terms Σ n_i."""
        return int(sum(self.orders))

    @property
    def hull(self) -> LineHull:
        """Convex hull of the sampled segments (where the model is meant to be used)."""
        self._require_fit()
        if self._hull is None:
            self._hull = self.plan.hull()
        return self._hull

    def contains(self, X: Any) -> np.ndarray:
        """Whether points X (caller's units, (n, d)) lie in the hull of the sampled segments, shape (n,)."""
        return self.hull.contains(X)

    def _local(self, d: Any) -> tuple[np.ndarray, np.ndarray]:
        """Each line's local sample index k = d − shift, and k clipped to the line's sampled range."""
        d = np.asarray(d, dtype=float).reshape(-1)
        k = d[:, None] - self.shifts[None, :]
        if self.extrapolation == "exponential":
            return k, k
        last = (self.plan.k_ranges[:, 1] - self.plan.k_ranges[:, 0]).astype(float)
        return k, np.clip(k, 0.0, last[None, :])

    def line_values(self, d: Any) -> np.ndarray:
        """The per-line models f_i at positions d (sample steps), shape (n, l).

        Within its samples a line's model is its sum of exponentials; beyond them, with ``extrapolation="linear"``
        (the default), it continues along its end tangent.  Lines of unequal length would otherwise extrapolate
        exponentials inside the hull, where a term with |z| > 1 grows without bound.
        """
        self._require_fit()
        k, kc = self._local(d)
        cols = []
        for i, f in enumerate(self.fits):
            value = f(kc[:, i])
            if self.extrapolation == "linear":
                value = value + f.derivative(kc[:, i]) * (k[:, i] - kc[:, i])
            cols.append(value)
        return np.stack(cols, axis=1)

    def line_derivatives(self, d: Any) -> np.ndarray:
        """df_i/dd at positions d, shape (n, l) (data units per sample step)."""
        self._require_fit()
        _, kc = self._local(d)
        return np.stack([f.derivative(kc[:, i]) for i, f in enumerate(self.fits)], axis=1)

    # ------------------------------------------------------------------------------------------- evaluation
    def _points(self, X: Any) -> tuple[np.ndarray, bool]:
        self._require_fit()
        arr = np.asarray(X, dtype=float)
        single = arr.ndim == 1
        arr = np.atleast_2d(arr)
        if arr.ndim != 2 or arr.shape[1] != self.plan.dim:
            raise SurrogateError(f"points must have shape (n, {self.plan.dim}), got {np.shape(X)}")
        return arr, single

    def predict_coordinates(self, P: Any, d: Any) -> np.ndarray:
        """Model values at plan coordinates: P (n, d − 1) in caller's units and d (n,) in sample steps."""
        self._require_fit()
        L = self.blend.lagrange(np.atleast_2d(np.asarray(P, dtype=float)))
        return np.einsum("ni,ni->n", L, self.line_values(d))

    def gradient_coordinates(self, P: Any, d: Any) -> np.ndarray:
        """Gradient with respect to (P, d), shape (n, d): columns ∂T/∂P_v then ∂T/∂d."""
        self._require_fit()
        P = np.atleast_2d(np.asarray(P, dtype=float))
        L = self.blend.lagrange(P)
        dL = self.blend.lagrange_gradient(P)
        F = self.line_values(d)
        dF = self.line_derivatives(d)
        return np.column_stack([np.einsum("niv,ni->nv", dL, F), np.einsum("ni,ni->n", L, dF)])

    def predict(self, X: Any) -> np.ndarray | float:
        """Model values at points X.

        Parameters
        ----------
        X : (n, d) or (d,) array
            Points, coordinates in the caller's units.

        Returns
        -------
        (n,) array, or float for a single point (data units).

        Notes
        -----
        The model is meant for the hull of the sampled segments (:meth:`contains`); outside it the values are
        extrapolations (no warning is given, so vectorised callers are not slowed down).
        """
        pts, single = self._points(X)
        P, d = self.plan.coordinates(pts)
        out = self.predict_coordinates(P, d)
        return float(out[0]) if single else out

    def gradient(self, X: Any) -> np.ndarray:
        """Gradient ∂T/∂X at points X, shape (n, d) or (d,) for a single point (data units per caller's unit)."""
        pts, single = self._points(X)
        P, d = self.plan.coordinates(pts)
        g = self.gradient_coordinates(P, d)
        # Chain rule: P = E (X − o), d = <Δ, X − o>/‖Δ‖².
        jac = np.vstack([self.plan.normal_basis, self.plan.direction / self.plan.spacing**2])
        out = g @ jac
        return out[0] if single else out

    __call__ = predict

    # ------------------------------------------------------------------------------------------------- JSON
    # The format itself lives in surrogate/model_file.py, beside its version number.
    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly representation of the options and the fitted model."""
        self._require_fit()
        return model_to_dict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SparseExponentialModel:
        """Inverse of :meth:`to_dict` (no refit)."""
        return model_from_dict(cls, data)

    def save(self, path: str | Path) -> None:
        """Write the fitted model to a JSON file at ``path``."""
        write_model(self, path)

    @classmethod
    def load(cls, path: str | Path) -> SparseExponentialModel:
        """Read a model written by :meth:`save`."""
        return read_model(cls, path)
