"""Replace some methods' runs in a ``mechopt compare`` result by a newer run of those methods, and rewrite its tables.

When one method changes, the other methods' runs (same study, budgets, seeds and code) stay valid; running them
again costs the Gaussian-process methods most of an hour on the multimodal suite.  This keeps the base runs of every
method the newer file does not contain, takes the newer file's runs for the methods it does, and writes
compare.json, compare.md and figures/compare_gaps.png into ``--out`` exactly as ``mechopt compare`` would::

    python -m benchmarks.compare_merge runs/suite/hartmann3/compare.json runs/suite_mg/hartmann3/compare.json \\
        --out runs/suite_merged/hartmann3
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mechopt.optimize.ground_truth import GroundTruth
from mechopt.studies import comparison as cmp
from mechopt.studies.catalogue import load_study


def main() -> None:
    """Merge the runs, write the comparison's files into ``--out``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("base", type=Path, help="compare.json with every method")
    parser.add_argument("newer", type=Path, help="compare.json whose methods replace the base's")
    parser.add_argument("--out", type=Path, required=True, help="folder of the merged comparison")
    args = parser.parse_args()
    try:
        base, newer = json.loads(args.base.read_text()), json.loads(args.newer.read_text())
    except (OSError, ValueError) as exc:
        raise SystemExit(f"error: cannot read a compare.json: {exc}") from None
    if base["study"] != newer["study"] or base["seeds"] != newer["seeds"]:
        raise SystemExit(f"error: {args.base} is {base['study']} with {base['seeds']} seeds, {args.newer} is "
                         f"{newer['study']} with {newer['seeds']}; expected the same study and seeds")
    replaced = {r["method"] for r in newer["runs"]}
    runs = [cmp.Run(**r) for r in newer["runs"]] + [cmp.Run(**r) for r in base["runs"] if r["method"] not in replaced]
    order = list(dict.fromkeys(r["method"] for r in base["runs"]))
    runs.sort(key=lambda r: (order.index(r.method) if r.method in order else -1, r.budget, r.seed))
    study = load_study(base["study"], {})
    engine = study.section("compare").get("engine")
    if engine:  # the engine the comparison ran on, as `mechopt compare` chooses it
        study = load_study(base["study"], {"engine": engine})
    md, fig = cmp.write(runs, GroundTruth(**base["truth"]), args.out, study, base["seeds"])
    print(md.read_text())
    print(f"merged {sorted(replaced)} from {args.newer} into {args.base}: {md}, {fig}")


if __name__ == "__main__":
    main()
