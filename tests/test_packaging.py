"""The wheel ships one import package, mechopt, with every subpackage and every packaged study's data."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _config() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_every_subpackage_is_listed_and_nothing_else():
    listed = set(_config()["tool"]["setuptools"]["packages"])
    found = {"mechopt"}
    for top in ("sim", "surrogate", "optimize", "runs", "studies", "report", "cli"):
        for init in (ROOT / top).rglob("__init__.py"):
            found.add("mechopt." + ".".join(init.parent.relative_to(ROOT).parts))
    assert listed == found, f"listed only: {sorted(listed - found)}; not listed: {sorted(found - listed)}"
    assert all(name == "mechopt" or name.startswith("mechopt.") for name in listed)


def test_every_packaged_study_file_and_its_data_are_package_data():
    patterns = _config()["tool"]["setuptools"]["package-data"]["mechopt.studies"]
    for study in (ROOT / "studies").glob("*/study.toml"):
        for f in study.parent.iterdir():
            if f.is_file() and f.suffix in (".toml", ".csv", ".md", ".json"):
                assert any(f.match("*/" + p.split("/")[-1]) for p in patterns), f


def test_the_console_script_points_into_mechopt():
    assert _config()["project"]["scripts"]["mechopt"] == "mechopt.cli.main:main"
