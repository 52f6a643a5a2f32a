"""The plan's table of the methods' own computing time: measured rows read back, budgets interpolated (issue 52)."""

from __future__ import annotations

import json

import pytest

from mechopt.studies.method_time import TABLE_FILE, method_seconds, method_time_line

ROWS = json.loads(TABLE_FILE.read_text())["rows"]


def test_the_table_has_rows_for_the_default_methods():
    assert {r["method"] for r in ROWS} >= {"auto", "sparse", "differential_evolution"}


@pytest.mark.parametrize("row", ROWS, ids=lambda r: f"{r['method']}-{r['dim']}-{r['budget']}")
def test_each_measured_row_reads_back(row):
    assert method_seconds(row["method"], row["dim"], row["budget"]) == pytest.approx(row["seconds"])


def test_budgets_between_and_beyond_the_measured_ones():
    method, dim = ROWS[0]["method"], ROWS[0]["dim"]
    points = sorted((r["budget"], r["seconds"]) for r in ROWS if r["method"] == method and r["dim"] == dim)
    (b0, s0), (b1, s1) = points[0], points[-1]
    if b1 > b0:
        assert method_seconds(method, dim, (b0 + b1) // 2) == pytest.approx(s0 + (s1 - s0) * ((b0 + b1) // 2 - b0)
                                                                             / (b1 - b0))
    assert method_seconds(method, dim, 2 * b1) == pytest.approx(2 * s1)  # in proportion beyond
    assert method_seconds(method, dim + 100, b0) == pytest.approx(
        method_seconds(method, max(r["dim"] for r in ROWS if r["method"] == method), b0))  # the nearest dimension
    assert method_seconds("no-such-method", dim, b0) is None


def test_the_plan_line_adds_the_simulations():
    assert "expected wall time about 2 min in all" in method_time_line(90.0, 30.0)
    assert "not measured" in method_time_line(None, 30.0)
