"""Where numba keeps its compiled kernels: a user cache folder, never the installed package.

``@njit(cache=True)`` writes its cache next to the module unless ``NUMBA_CACHE_DIR`` says otherwise.  Inside
site-packages that leaves folders behind when the package is uninstalled or replaced by an editable install, and
those folders then shadow the real package (the Quick start's second command broke the CLI that way).  This module is
imported by ``mechopt/__init__`` before any kernel is compiled.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path


def numba_cache_dir() -> Path:
    """The folder numba caches mechopt's kernels in.

    Returns
    -------
    Path
        ``$NUMBA_CACHE_DIR`` when the user set it, else ``$XDG_CACHE_HOME/mechopt/numba`` (default
        ``~/.cache/mechopt/numba``).
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "mechopt" / "numba"


def use_user_cache() -> None:
    """Point numba's cache at :func:`numba_cache_dir` (also when numba was imported before mechopt)."""
    os.environ["NUMBA_CACHE_DIR"] = str(numba_cache_dir())
    if "numba" in sys.modules:
        from numba.core import config

        config.reload_config()
