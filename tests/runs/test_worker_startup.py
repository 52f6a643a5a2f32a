"""A script's worker start-up mistakes end in one line, and a SIGTERM leaves nothing leaked (issue 52).

Real scripts in real subprocesses, with real worker processes.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mechopt.runs.main_guard import _guarded_lines
from mechopt.runs.store import SampleStore

PROBLEM = '''
import time
import mechopt

class Bowl(mechopt.DesignProblem):
    name = "bowl"
    variables = (mechopt.Variable("a", 0.0, 4.0, "mm"), mechopt.Variable("b", 0.0, 4.0, "mm"))
    outputs = ("f",)
    objective = "f"
    delay = {delay}

    def evaluate(self, x):
        time.sleep(self.delay)
        return {{"f": float((x[0] - 1) ** 2 + (x[1] - 2) ** 2)}}
'''

UNGUARDED = PROBLEM + '''
print(mechopt.minimize(Bowl(), budget=12, workers=2).fun)
'''

UNGUARDED_IN_A_FUNCTION = PROBLEM + '''
def main():
    print(mechopt.minimize(Bowl(), budget=12, workers=2).fun)

main()
'''

GUARDED = PROBLEM + '''
if __name__ == "__main__":
    import sys
    print("started", flush=True)
    print(mechopt.minimize(Bowl(), budget=int(sys.argv[1]), workers=2, store=sys.argv[2]).fun, flush=True)
'''


def run_script(folder: Path, text: str, *args: str, delay: float = 0.0, timeout: float = 120.0):
    script = folder / "script.py"
    script.write_text(text.format(delay=delay))
    return subprocess.run([sys.executable, str(script), *args], capture_output=True, text=True, timeout=timeout,
                          cwd=folder, env={**os.environ, "PYTHONWARNINGS": "default"})


@pytest.mark.parametrize("text", [UNGUARDED, UNGUARDED_IN_A_FUNCTION], ids=["top-level", "in-a-function"])
def test_an_unguarded_script_ends_in_one_line_before_any_worker(tmp_path, text):
    start = time.perf_counter()
    proc = run_script(tmp_path, text)
    assert proc.returncode == 1 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("mechopt: error: workers = 2 start processes that import the main script script.py")
    assert 'under `if __name__ == "__main__":`' in lines[0]
    assert time.perf_counter() - start < 30  # no worker started (today's pool broke after some 14 s)


def test_a_guarded_script_runs_its_workers(tmp_path):
    proc = run_script(tmp_path, GUARDED, "12", str(tmp_path / "s.sqlite"))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[0] == "started" and float(proc.stdout.splitlines()[1]) < 1.0
    assert "leaked" not in proc.stderr and "Traceback" not in proc.stderr


def test_sigterm_ends_the_run_cleanly_and_keeps_the_store(tmp_path):
    script = tmp_path / "script.py"
    script.write_text(GUARDED.format(delay=0.3))
    store = tmp_path / "s.sqlite"
    proc = subprocess.Popen([sys.executable, str(script), "200", str(store)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    assert proc.stdout.readline().strip() == "started"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and stored(store) < 2:  # the pool is up and simulating
        time.sleep(0.2)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=60)  # waits for the resource tracker too: it shares the stderr pipe
    assert proc.returncode == 128 + signal.SIGTERM
    assert "leaked" not in err and "resource_tracker" not in err and "Traceback" not in err, err
    assert 2 <= stored(store) < 200


def stored(path: Path) -> int:
    """Designs in the store (0 before it exists)."""
    if not path.exists():
        return 0
    with SampleStore(path) as store:
        return store.count()


def test_the_guard_reader_knows_both_ways_round():
    source = 'x = 1\nif __name__ == "__main__":\n    run()\n    more()\nif "__main__" == __name__:\n    again()\n'
    assert _guarded_lines(source) == [(3, 4), (6, 6)]
    assert _guarded_lines('if __name__ != "__main__":\n    run()\n') == []
