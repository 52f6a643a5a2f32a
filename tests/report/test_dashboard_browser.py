"""The live page in a real browser (Debian's chromium driven by Playwright) against a ventilator study running in the
background: the count of simulations grows on the page between two looks, nothing is fetched from outside
127.0.0.1, and the screenshot is not blank.

Set ``MECHOPT_DASHBOARD_SCREENSHOT=path.png`` to keep the screenshot.
"""

from __future__ import annotations

import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import time
from contextlib import closing
from pathlib import Path
from urllib.parse import urlparse

import numpy as np
import pytest

CHROMIUM = "/usr/bin/chromium"

if not Path(CHROMIUM).is_file() or not shutil.which("chromium"):
    if os.environ.get("CI"):
        raise RuntimeError(f"the browser test needs {CHROMIUM} (apt-get install chromium): .ci/run installs it")
    pytest.skip(f"no {CHROMIUM} (apt-get install chromium)", allow_module_level=True)
if os.environ.get("CI"):
    import playwright.sync_api  # noqa: F401  (CI must have it: an ImportError fails the run)
sync_api = pytest.importorskip("playwright.sync_api")
pytest.importorskip("plotly")


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _rows(store: Path) -> int:
    """Records in the store, once the run has written its journal (0 before)."""
    if not store.is_file():
        return 0
    try:
        with closing(sqlite3.connect(f"file:{store}?mode=ro", uri=True, timeout=5)) as conn:
            conn.execute("SELECT COUNT(*) FROM runs")
            return conn.execute("SELECT COUNT(*) FROM samples").fetchone()[0]
    except sqlite3.OperationalError:
        return 0


@pytest.fixture
def running_study(tmp_path):
    """A ventilator study writing to its store in the background: differential evolution on the analytic engine
    simulates one design after the other (tens a second), and its budget outlasts the test."""
    store = tmp_path / "samples.sqlite"
    cmd = [sys.executable, "-m", "mechopt.cli.main", "study", "ventilator", "--engine", "analytic", "--method",
           "differential_evolution", "--workers", "1", "--no-progress", "--budget", "3000", "--lines", "0",
           "--seed", "3", "--out", str(tmp_path / "out"), "--store", str(store)]
    errors = tmp_path / "study.stderr"
    with open(errors, "wb") as err:  # a file, not a pipe: a pipe nobody reads would block the study once full
        proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=err)
    try:
        deadline = time.monotonic() + 60
        while _rows(store) < 1:
            assert proc.poll() is None, f"the study stopped: {errors.read_text()[-500:]}"
            assert time.monotonic() < deadline, "the study wrote no simulation in 60 s"
            time.sleep(0.3)
        yield store
    finally:
        _stop(proc)


@pytest.fixture
def dashboard(running_study):
    proc = subprocess.Popen([sys.executable, "-m", "mechopt.cli.main", "dashboard", str(running_study), "--port", "0",
                             "--refresh", "0.5"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        assert " at http://127.0.0.1:" in line, f"{line!r} {proc.stderr.read() if proc.poll() is not None else ''}"
        yield line.split(" at ")[1].split()[0]
    finally:
        _stop(proc)


def _done(page) -> int:
    page.wait_for_function("() => /^\\d+$/.test(document.getElementById('done').textContent)", timeout=30_000)
    return int(page.inner_text("#done"))


def test_the_page_follows_a_running_study(dashboard, tmp_path):
    outside: list[str] = []
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu",
                                                                     "--disable-background-networking"])
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})

            def only_here(route):
                if urlparse(route.request.url).hostname == "127.0.0.1":
                    route.continue_()
                else:
                    outside.append(route.request.url)
                    route.abort()

            page.route("**/*", only_here)
            page.goto(dashboard)
            first = _done(page)
            page.wait_for_function(f"() => Number(document.getElementById('done').textContent) > {first}",
                                   timeout=40_000)
            second = _done(page)
            assert second > first
            assert page.inner_text("#state") == "running"
            assert "ventilator" in page.inner_text("#study")
            assert "plan: budget 3000 simulations" in page.inner_text("#plan")
            # Plotly drew the parallel coordinates (its SVG) with the variables' axes.
            page.wait_for_selector("#parallel .parcoords", timeout=20_000)
            assert "oa (mm)" in page.inner_text("#parallel")
            shot = tmp_path / "dashboard.png"
            page.screenshot(path=str(shot), full_page=True)
        finally:
            browser.close()
    assert outside == []
    from PIL import Image

    rgb = np.asarray(Image.open(shot).convert("RGB"), dtype=np.uint32)
    assert rgb.shape[0] >= 1000 and rgb.shape[1] == 1400
    assert rgb.std() > 25  # not blank: dark header, white panels, coloured lines (0 to 255)
    assert len(np.unique(rgb[..., 0] << 16 | rgb[..., 1] << 8 | rgb[..., 2])) > 200
    keep = os.environ.get("MECHOPT_DASHBOARD_SCREENSHOT")
    if keep:
        shutil.copy(shot, keep)
