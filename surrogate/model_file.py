"""The versioned JSON format of a fitted :class:`~mechopt.surrogate.model.SparseExponentialModel`.

A saved model holds its options, its plan, every line's exponential fit, the line shifts and the blend, so it is
read back without refitting.  ``format`` names the class and ``version`` the layout; a file of another format or
version is refused rather than half read.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from mechopt.surrogate.blending import ChebyshevBlend
from mechopt.surrogate.errors import SurrogateError
from mechopt.surrogate.exponential_fit import ExponentialFit
from mechopt.surrogate.lines import LinePlan

if TYPE_CHECKING:
    from mechopt.surrogate.model import SparseExponentialModel

    Model = TypeVar("Model", bound=SparseExponentialModel)

FORMAT = "mechopt.surrogate.SparseExponentialModel"
VERSION = 1


def model_to_dict(model: SparseExponentialModel) -> dict[str, Any]:
    """JSON-friendly representation of a fitted model's options and fitted state (see the module docstring)."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "options": {
            "order": model.order if model.order is None or np.ndim(model.order) == 0 else list(model.order),
            "method": model.method,
            "solver": model.solver,
            "max_order": model.max_order,
            "cond_max": model.cond_max,
            "extrapolation": model.extrapolation,
        },
        "plan": model.plan.to_dict(),
        "shifts": model.shifts.tolist(),
        "fits": [f.to_dict() for f in model.fits],
        "blend": model.blend.to_dict(),
    }


def model_from_dict(cls: type[Model], data: dict[str, Any]) -> Model:
    """Inverse of :func:`model_to_dict`: a fitted instance of ``cls`` (no refit).

    Raises
    ------
    SurrogateError
        Another format or version, or fits that do not match the plan's lines.
    """
    if data.get("format") != FORMAT:
        raise SurrogateError(f"not a saved SparseExponentialModel (format {data.get('format')!r})")
    if data.get("version") != VERSION:
        raise SurrogateError(f"unsupported model file version {data.get('version')!r}, expected {VERSION}")
    model = cls(**data["options"])
    model.plan = LinePlan.from_dict(data["plan"])
    model.fits = [ExponentialFit.from_dict(f) for f in data["fits"]]
    model.shifts = np.asarray(data["shifts"], dtype=float)
    model.blend = ChebyshevBlend.from_dict(data["blend"])
    if len(model.fits) != model.plan.n_lines or model.shifts.size != model.plan.n_lines:
        raise SurrogateError(f"saved model has {len(model.fits)} fits for {model.plan.n_lines} lines")
    return model


def write_model(model: SparseExponentialModel, path: str | Path) -> None:
    """Write a fitted model to a JSON file at ``path``."""
    Path(path).write_text(json.dumps(model.to_dict(), indent=1))


def read_model(cls: type[Model], path: str | Path) -> Model:
    """Read a model written by :func:`write_model` as an instance of ``cls``.

    Raises
    ------
    SurrogateError
        The file cannot be read or is not JSON (and every error of :func:`model_from_dict`).
    """
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise SurrogateError(f"cannot read model file {str(path)!r}: {exc}") from exc
    return cls.from_dict(data)
