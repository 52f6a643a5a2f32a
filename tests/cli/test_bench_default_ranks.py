"""benchmarks/bench_default.py's two-sample verdict: how often the default ends lower than a peer, and the
Mann-Whitney p-value, against values computed by hand."""

import json


def _write(path, gaps_by_method):
    with path.open("w") as fh:
        for method, gaps in gaps_by_method.items():
            for seed, gap in enumerate(gaps):
                fh.write(json.dumps({"function": "f", "dim": 3, "method": method, "budget": 30, "seed": seed,
                                     "gap": gap}) + "\n")


def _row(capsys, peer):
    lines = capsys.readouterr().out.splitlines()
    return next(line.split() for line in lines if line.startswith("f ") and f" {peer} " in line)


def test_separated_samples(tmp_path, capsys):
    from benchmarks.bench_default import rank_test

    path = tmp_path / "runs.jsonl"
    # Every run of auto below every run of "low", above every run of "high": P = 1 and 0; the exact two-sided
    # p-value of 3 against 3 fully separated runs is 2 / C(6, 3) = 0.1.
    _write(path, {"auto": [1.0, 2.0, 3.0], "high": [4.0, 5.0, 6.0], "low": [0.1, 0.2, 0.3]})
    rank_test(path)
    out = capsys.readouterr().out
    rows = {line.split()[3]: line.split() for line in out.splitlines() if line.startswith("f ")}
    assert float(rows["high"][4]) == 1.0 and float(rows["high"][5]) == 0.1
    assert float(rows["low"][4]) == 0.0 and float(rows["low"][5]) == 0.1


def test_ties_count_half_and_a_raised_run_ranks_last(tmp_path, capsys):
    from benchmarks.bench_default import rank_test

    path = tmp_path / "runs.jsonl"
    # Pairs (auto, peer): 1 vs 1 tie (½), 1 vs inf win, 5 vs 1 loss, 5 vs inf win: (½ + 1 + 0 + 1) / 4 = 0.625.
    _write(path, {"auto": [1.0, 5.0], "peer": [1.0, float("inf")]})
    rank_test(path)
    row = _row(capsys, "peer")
    assert abs(float(row[4]) - 0.625) < 0.006  # printed to two decimals
