"""What a run leaves for a person: ``study_report.py`` (result.json, report.md) and ``plots.py`` (figures)."""
