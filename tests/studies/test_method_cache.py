"""A study re-run with every simulation in the store replays its method's answer; anything changed computes again
(issue 52)."""

from __future__ import annotations

import json
import sqlite3

from mechopt.cli.main import main
from mechopt.studies.method_cache import CACHE_FILE


def study(out, capsys, *extra: str) -> tuple[list[str], dict]:
    code = main(["study", "branin", "--budget", "30", "--method", "sparse", "--workers", "1", "--no-progress",
                 "--lines", "0", "--out", str(out), *extra])
    assert code == 0
    printed = capsys.readouterr().out.splitlines()
    return printed, json.loads((out / "result.json").read_text())


def test_a_rerun_replays_and_gives_the_same_answer(tmp_path, capsys):
    out = tmp_path / "b"
    first, r1 = study(out, capsys)
    assert not any("replayed" in line for line in first) and (out / CACHE_FILE).is_file()
    again, r2 = study(out, capsys)
    assert any("sparse: every one of its 30 simulations is in the store, unchanged" in line for line in again)
    assert r2["optimum"] == r1["optimum"] and r2["history"] == r1["history"] and r2["message"] == r1["message"]
    assert r2["simulations"]["new"] == 0 and r2["simulations"]["reused"] == r1["simulations"]["new"]


def test_another_seed_or_a_changed_record_computes_again(tmp_path, capsys):
    out = tmp_path / "b"
    study(out, capsys)
    printed, _ = study(out, capsys, "--seed", "3")
    assert not any("replayed" in line for line in printed)
    printed, _ = study(out, capsys, "--seed", "3")
    assert any("replayed" in line for line in printed)
    with sqlite3.connect(out / "samples.sqlite") as db:  # the stored outputs change: the answer is not determined
        for rowid, outputs in db.execute("SELECT rowid, outputs FROM samples").fetchall():
            changed = {**json.loads(outputs), "f": 1.5 * json.loads(outputs)["f"] + 1.0}
            db.execute("UPDATE samples SET outputs = ? WHERE rowid = ?", (json.dumps(changed), rowid))
    db.close()
    printed, _ = study(out, capsys, "--seed", "3")
    assert not any("replayed" in line for line in printed)
