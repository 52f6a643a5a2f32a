"""Overhead per design of a simulator run as an external command or a Python callable, against in-process.

A trivial evaluator (a quadratic) four ways — in-process, as a callable, as a command over stdio, as a command with
files — median of many calls each; then the ventilator with Exudyn in-process and through the packaged
``ventilator-command`` study (one Python process per design).  Run: ``python benchmarks/bench_command.py [N]``.
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from mechopt.studies.catalogue import load_study

SIM = "import json, sys\nd = json.load(open('design.json')) if '--files' in sys.argv else json.load(sys.stdin)\n" \
      "out = json.dumps({'f': (d['a'] - 1) ** 2 + d['b']})\n" \
      "open('outputs.json', 'w').write(out) if '--files' in sys.argv else print(out)\n"
FUNC = "def simulate(d):\n    return {'f': (d['a'] - 1) ** 2 + d['b']}\n"


def median_ms(fn, n: int) -> float:
    times = []
    for i in range(n):
        x = np.array([0.5 + 1e-3 * i, 1.0])
        t0 = time.perf_counter()
        fn(x)
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def study(folder: Path, simulator: str) -> Path:
    toml = folder / f"{abs(hash(simulator))}.toml"
    toml.write_text(f'name = "bench"\nkind = "external"\n[variables]\na = [0.0, 2.0]\nb = [0.0, 2.0]\n'
                    f'[simulator]\noutputs = ["f"]\n{simulator}\n')
    return toml


def main(n: int = 50) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "sim.py").write_text(SIM)
        (folder / "bench_func.py").write_text(FUNC)
        rows = [("trivial, in-process", lambda x: {"f": (x[0] - 1) ** 2 + x[1]})]
        for label, sim in [("trivial, Python callable", 'callable = "bench_func:simulate"'),
                           ("trivial, command (stdio)", 'command = ["{python}", "sim.py"]'),
                           ("trivial, command (files)", 'command = ["{python}", "sim.py", "--files"]\n'
                                                        f'exchange = "files"\nworkdir = "{folder / "runs"}"')]:
            rows.append((label, load_study(study(folder, sim)).problem.evaluate))
        print(f"| evaluator | median per design (ms), n = {n} |")
        print("|---|---:|")
        for label, fn in rows:
            print(f"| {label} | {median_ms(fn, n):.3f} |")
    original = np.array([53.0, 65.0, 282.0])
    inproc = load_study("ventilator", {"engine": "exudyn"}).problem
    command = load_study("ventilator-command").problem
    command.evaluate(original)  # fills the script's cache of the reconstructed ventilator
    inproc.evaluate(original)
    m = max(3, n // 10)
    for label, fn in [("ventilator, Exudyn in-process", inproc.evaluate),
                      ("ventilator, Exudyn via command", command.evaluate)]:
        times = []
        for i in range(m):
            t0 = time.perf_counter()
            fn(original + np.array([-0.1 * i, 0.0, 0.0]))
            times.append(time.perf_counter() - t0)
        print(f"| {label} (n = {m}) | {1e3 * statistics.median(times):.1f} |")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 50)
