"""The sparse model of a problem's objective, fitted to the objective or its square, answering in the objective.

It wraps :class:`~mechopt.surrogate.SparseExponentialModel` (which works in the model's coordinates U) with the
permutation from designs to U and the choice of fit, and is saved as versioned JSON.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from mechopt.errors import InputError
from mechopt.surrogate import SparseExponentialModel
from mechopt.surrogate.errors import SurrogateError

__all__ = ["ObjectiveModel"]

_FORMAT = "mechopt.studies.ObjectiveModel"
_VERSION = 2


class ObjectiveModel:
    """A fitted sparse model of the objective.

    Parameters
    ----------
    model : SparseExponentialModel
        Fitted on the objective (``fit="value"``) or its square (``fit="square"``), in model coordinates.
    fit : str
        ``"value"`` or ``"square"``.
    order : sequence of int
        Design variable behind each model coordinate.
    variables : sequence of str
        The design variables' names (checked when a saved model is used for a study).
    """

    def __init__(self, model: SparseExponentialModel, fit: str, order: Any, variables: Any = ()) -> None:
        if fit not in ("value", "square"):
            raise InputError(f"fit = {fit!r}; expected 'value' or 'square'")
        self.model = model
        self.fit = fit
        self.order = np.asarray(order, dtype=int)
        self.variables = tuple(variables)

    @property
    def plan(self):
        """The model's line plan (model coordinates)."""
        return self.model.plan

    @property
    def orders(self):
        """Exponential orders of the lines."""
        return self.model.orders

    def to_u(self, X: np.ndarray) -> np.ndarray:
        """Designs -> model coordinates."""
        return np.asarray(X, dtype=float)[..., self.order]

    def from_u(self, U: np.ndarray) -> np.ndarray:
        """Model coordinates -> designs."""
        return np.asarray(U, dtype=float)[..., np.argsort(self.order)]

    def predict_u(self, U: np.ndarray) -> np.ndarray:
        """The objective at model coordinates U (n, d)."""
        value = np.asarray(self.model.predict(np.atleast_2d(U)), dtype=float)
        return np.sqrt(np.maximum(value, 0.0)) if self.fit == "square" else value

    def predict(self, X: np.ndarray) -> np.ndarray:
        """The objective at designs X (n, d), in the problem's units."""
        return self.predict_u(self.to_u(np.atleast_2d(X)))

    def contains(self, X: np.ndarray) -> np.ndarray:
        """Designs (n, d) inside the hull of the model's lines."""
        return self.model.contains(self.to_u(np.atleast_2d(X)))

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict (format and version first)."""
        return {"format": _FORMAT, "version": _VERSION, "fit": self.fit, "order": self.order.tolist(),
                "variables": list(self.variables), "model": self.model.to_dict()}

    def save(self, path: str | Path) -> Path:
        """Write the model as JSON; returns the path."""
        path = Path(path)
        try:
            path.write_text(json.dumps(self.to_dict()))
        except OSError as exc:
            raise InputError(f"cannot write the model {path}: {exc.strerror or exc}") from None
        return path

    @classmethod
    def load(cls, path: str | Path) -> ObjectiveModel:
        """Read a model saved by :meth:`save`.

        Raises
        ------
        InputError
            A missing, truncated or foreign file, or a model of another format version (one line each).
        """
        path = Path(path)
        try:
            data = json.loads(path.read_text())
        except FileNotFoundError:
            raise InputError(f"no model at {path}: run `mechopt study` first (or pass --refit)") from None
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise InputError(f"{path} is not a readable model file ({exc}); rerun with --refit to rebuild it") from None
        if not isinstance(data, dict) or data.get("format") != _FORMAT:
            raise InputError(f"{path} is not a mechopt model file; rerun with --refit to rebuild it")
        if data.get("version") != _VERSION:
            raise InputError(f"{path} is a model of format version {data.get('version')!r}, this mechopt reads "
                             f"version {_VERSION}; rerun with --refit to rebuild it")
        try:
            model = SparseExponentialModel.from_dict(data["model"])
            return cls(model, data["fit"], data["order"], data.get("variables", ()))
        except (KeyError, TypeError, ValueError, SurrogateError) as exc:
            raise InputError(f"{path} holds a damaged model ({exc}); rerun with --refit to rebuild it") from None
