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
