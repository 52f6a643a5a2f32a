"""The README is the door and BENCHMARKS.md the current figures: both stay short (the rest is the docs site)."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize(("name", "limit"), [("README.md", 250), ("BENCHMARKS.md", 400)])
def test_the_page_stays_within_its_length(name, limit):
    lines = (ROOT / name).read_text().splitlines()
    assert len(lines) <= limit, f"{name} has {len(lines)} lines; move the detail to docs/guide/ (at most {limit})"


def test_the_site_index_takes_every_guide_page_by_a_glob():
    index = (ROOT / "docs" / "index.md").read_text()
    assert ":glob:" in index and "guide/*" in index
