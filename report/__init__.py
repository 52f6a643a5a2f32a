"""What a run leaves for a person: ``study_report.py`` (result.json, report.md), ``plots.py`` (figures) and
``comparison_figures.py`` (the figures of ``mechopt compare``)."""
