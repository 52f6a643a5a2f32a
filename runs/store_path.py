"""A sample store's path as a user gives it: its folder must exist.

A store path whose folder does not exist is refused rather than made silently: a typo in ``--store`` would otherwise
start a run on an empty store somewhere unexpected, and a later run pointed at the intended path would not find its
simulations.  (:class:`~mechopt.runs.store.SampleStore` itself still makes the folder: programs choose their paths.)
"""

from __future__ import annotations

import os
from pathlib import Path

from mechopt.errors import InputError

__all__ = ["check_store_folder"]


def check_store_folder(store: str | os.PathLike, option: str = "--store") -> None:
    """Refuse a sample store path whose folder does not exist (it is not made silently).

    Parameters
    ----------
    store : path
        The store's path.
    option : str, optional
        How the user gave it (``--store``, ``store``), for the message.

    Raises
    ------
    InputError
        One line naming the missing folder.
    """
    folder = Path(store).parent
    if not folder.is_dir():
        what = "is a file" if folder.exists() else "does not exist"
        raise InputError(f"{option} {store}: the folder {folder} {what}; create it first or choose another path")
