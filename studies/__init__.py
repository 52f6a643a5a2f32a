"""The catalogue of studies and the running of one: one folder per study (``study.toml``, its data, its README), the
readers of each mechanism kind (``kinds/``), the registry of kinds, the study-file loader (``catalogue.py``,
``study_file.py``) and the multimodal test functions; the runner of a whole study (``runner.py``: plan, optimise,
validate, report), its plan (``plan.py``), its options and first lines (``run_options.py``, ``run_header.py``), and
the optimizer comparison (``comparison/``).  A new study is a folder here."""
