"""CI: the installed (non-editable) mechopt claims one import name: every file of its RECORD lies in mechopt/, its
dist-info, or is the console script."""

from __future__ import annotations

import sys
from importlib.metadata import distribution

files = [str(f) for f in distribution("mechopt").files or []]
bad = [f for f in files if not (f.startswith(("mechopt/", "mechopt-")) or f.startswith("../") and "bin/mechopt" in f)]
tops = sorted({f.split("/")[0] for f in files if not f.startswith("../")})
print(f"mechopt installs {len(files)} files under {tops}")
if bad or not any(f.startswith("mechopt/studies/ventilator/study.toml") for f in files):
    print(f"unexpected files outside mechopt/ (or the ventilator study missing): {bad[:10]}", file=sys.stderr)
    sys.exit(1)
