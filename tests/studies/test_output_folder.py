"""An output folder holding another study's results, and a store in a folder that does not exist, end in one line
with nothing overwritten or made (issue 52).  Real runs of ``mechopt study`` in subprocesses."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import mechopt
from mechopt.errors import InputError
from mechopt.studies.catalogue import load_study
from mechopt.studies.output_folder import check_output_owner


def study(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mechopt.cli.main", "study", *args, "--workers", "1",
                           "--no-progress", "--method", "auto", "--budget", "12"], capture_output=True, text=True,
                          env={**os.environ, "MPLBACKEND": "Agg"}, timeout=300)


def one_line(proc: subprocess.CompletedProcess, *expected: str) -> None:
    err = proc.stderr.strip()
    assert proc.returncode != 0 and "Traceback" not in err and len(err.splitlines()) == 1, err
    for text in expected:
        assert text in err, err


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def branin_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("runs") / "branin"
    proc = study("branin", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    return out


def test_another_study_is_refused_and_nothing_is_overwritten(branin_run):
    before = snapshot(branin_run)
    one_line(study("six_hump_camel", "--out", str(branin_run)), f"--out {branin_run} holds the results of study "
             "'branin'", "nothing was overwritten", "--force")
    assert snapshot(branin_run) == before


def test_the_same_study_runs_again_in_its_folder(branin_run):
    proc = study("branin", "--out", str(branin_run), "--seed", "1")
    assert proc.returncode == 0, proc.stderr


def test_another_problem_of_the_same_study_is_refused(branin_run):
    with pytest.raises(InputError, match="results of study 'branin' on another problem"):
        check_output_owner(branin_run, "branin", "0" * 64)
    check_output_owner(branin_run, "branin", load_study("branin").problem.fingerprint())  # its own: accepted


def test_force_replaces_the_other_study_outputs_and_keeps_the_store(tmp_path):
    out = tmp_path / "shared"
    assert study("branin", "--out", str(out)).returncode == 0
    stale = out / "figures" / "only_branin_made_this.png"
    stale.write_bytes(b"png")
    proc = study("six_hump_camel", "--out", str(out), "--force")
    assert proc.returncode == 0, proc.stderr
    assert json.loads((out / "result.json").read_text())["study"] == "six_hump_camel"
    assert not stale.exists() and (out / "samples.sqlite").is_file()
    with mechopt.SampleStore(out / "samples.sqlite") as store:  # both studies' simulations are kept
        counts = [len(store.records(load_study(name).problem.fingerprint())) for name in ("branin", "six_hump_camel")]
    assert counts[0] >= 12 and counts[1] >= 12


def test_a_store_in_a_missing_folder_is_refused_and_not_made(tmp_path):
    store = tmp_path / "nonexistent" / "dir" / "s.sqlite"
    one_line(study("branin", "--out", str(tmp_path / "out"), "--store", str(store)),
             f"--store {store}: the folder {store.parent} does not exist")
    assert not (tmp_path / "nonexistent").exists() and not (tmp_path / "out").exists()
    with pytest.raises(InputError, match="the folder .* does not exist"):
        mechopt.minimize(load_study("branin").problem, budget=12, store=store)
    assert not (tmp_path / "nonexistent").exists()
