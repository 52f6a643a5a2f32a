"""Saving a figure: the one place that turns a bad output path into a one-line error."""

from __future__ import annotations

from pathlib import Path

from mechopt.errors import InputError

#: File types a figure may be written as (matplotlib's Agg backend, plus Pillow for animations).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")


def figure_path(path: str | Path, suffixes: tuple[str, ...] = FIGURE_SUFFIXES) -> Path:
    """Check a figure's output path before any work: known suffix, a folder that exists or can be made, writable.

    Parameters
    ----------
    path : str or Path
        Where the figure goes.
    suffixes : tuple of str
        Accepted file suffixes.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        Unknown suffix, a parent that is a file, or a folder that cannot be written.
    """
    path = Path(path)
    if path.suffix.lower() not in suffixes:
        raise InputError(f"figure file {str(path)!r}: expected a name ending in {', '.join(suffixes)}")
    if path.is_dir():
        raise InputError(f"figure file {str(path)!r} is a folder; expected a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        raise InputError(f"cannot write {path}: a parent of it is a file, not a folder") from None
    except OSError as exc:
        raise InputError(f"cannot write {path}: {exc.strerror or exc}") from None
    import os

    if not os.access(path.parent, os.W_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise InputError(f"cannot write {path}: the folder {path.parent} is read-only")
    return path


def save_figure(fig, path: str | Path, dpi: int = 110) -> Path:
    """Write a finished matplotlib figure (110 dpi: readable at 100 % zoom) and release it.

    Raises
    ------
    InputError
        When the file cannot be written (see :func:`figure_path`).
    """
    import matplotlib.pyplot as plt

    try:
        path = figure_path(path)
        fig.savefig(path, dpi=dpi)
    except OSError as exc:
        raise InputError(f"cannot write {path}: {exc.strerror or exc}") from None
    finally:
        plt.close(fig)
    return path
