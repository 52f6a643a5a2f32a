"""One headline table and figure from several ``mechopt compare`` runs (each run's compare.json).

``mechopt compare --study A,B`` writes the headline itself; this joins runs made separately (different budgets per
study), without running anything again::

    python -m benchmarks.compare_headline runs/vent/compare.json runs/studies/*/compare.json --out docs
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mechopt.report.comparison_figures import plot_headline
from mechopt.studies.comparison import headline


def main() -> None:
    """Read the runs, write ``headline.md`` and ``compare_headline.png`` into ``--out``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path, help="compare.json files")
    parser.add_argument("--out", type=Path, default=Path("."), help="folder of headline.md and the figure")
    args = parser.parse_args()
    needed, budgets, unfinished = {}, {}, {}
    for path in args.runs:
        data = json.loads(path.read_text())
        needed[data["study"]] = data["needed"]
        unfinished[data["study"]] = set(data.get("unfinished_methods", []))
        budgets[data["study"]] = {m: max(r["budget"] for r in data["rows"] if r["method"] == m) for m in data["needed"]}
    args.out.mkdir(parents=True, exist_ok=True)
    text = headline(needed, budgets, unfinished)
    (args.out / "headline.md").write_text(text)
    fig = plot_headline(needed, budgets, args.out / "compare_headline.png", unfinished)
    print(text)
    print(f"written: {args.out / 'headline.md'}, {fig}")


if __name__ == "__main__":
    main()
