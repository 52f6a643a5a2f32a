"""load_study refuses overrides it would otherwise ignore or crash on, in one line naming them."""

from __future__ import annotations

import pytest

from mechopt import load_study
from mechopt.errors import StudyError


@pytest.mark.parametrize(("options", "expected"), [
    ({"engin": "analytic"}, "unknown override 'engin'; expected one of engine"),
    ("engine=analytic", "options = 'engine=analytic': expected a mapping"),
    (["engine"], "expected a mapping"),
])
def test_bad_overrides_are_one_line_errors(options, expected):
    with pytest.raises(StudyError) as info:
        load_study("ventilator", options)
    assert expected in str(info.value) and "\n" not in str(info.value)


def test_the_engine_override_is_taken():
    assert load_study("ventilator", {"engine": "analytic"}).problem.engine == "analytic"
    assert load_study("ventilator", {"engine": None}).problem.engine == "pymunk"  # the study file's own


def test_a_misspelt_section_is_refused_not_ignored(tmp_path):
    # `[surogate]` used to be read by nothing, and the study ran with the default line plan: the user's settings
    # were silently dropped.
    from mechopt.studies.catalogue import STUDIES_DIR

    text = (STUDIES_DIR / "ventilator" / "study.toml").read_text()
    assert "[surrogate]" in text
    path = tmp_path / "typo" / "study.toml"
    path.parent.mkdir()
    path.write_text(text.replace("[surrogate]", "[surogate]"))
    with pytest.raises(StudyError) as info:
        load_study(path)
    message = str(info.value)
    assert "unknown key surogate; kind 'four-bar' reads" in message and "surrogate" in message
    assert "\n" not in message
    top = tmp_path / "top" / "study.toml"
    top.parent.mkdir()
    top.write_text("nosuch = 3\n" + text)
    with pytest.raises(StudyError, match="unknown key nosuch"):
        load_study(top)
