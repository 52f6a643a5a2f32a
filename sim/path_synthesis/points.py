"""Desired points of a path-synthesis study: a CSV ``i,x,y`` read into an (N, 2) array with one-line errors."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from mechopt.errors import InputError

__all__ = ["read_points"]


def read_points(path: str | Path) -> np.ndarray:
    """The desired points of a CSV file with the header ``i,x,y`` (one point a row, in path order).

    Parameters
    ----------
    path : str or Path
        The CSV file.

    Returns
    -------
    (N, 2) ndarray
        x and y of each point (lengths), N >= 3.

    Raises
    ------
    InputError
        A missing file, another header, a row that is not three numbers, or fewer than 3 points.
    """
    path = Path(path)
    try:
        with open(path, newline="") as fh:
            rows = [row for row in csv.reader(fh) if row]
    except OSError as exc:
        raise InputError(f"cannot read desired points {path}: {exc.strerror or exc}") from None
    if not rows or [c.strip() for c in rows[0]] != ["i", "x", "y"]:
        raise InputError(f"{path.name}: expected the header 'i,x,y'")
    try:
        data = np.array([[float(c) for c in row] for row in rows[1:]], dtype=float)
    except ValueError:
        raise InputError(f"{path.name}: every row must be three numbers i,x,y") from None
    if data.ndim != 2 or data.shape[1] != 3 or data.shape[0] < 3 or not np.all(np.isfinite(data)):
        raise InputError(f"{path.name}: expected at least 3 rows of three finite numbers i,x,y")
    return data[:, 1:].copy()
