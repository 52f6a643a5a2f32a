"""The catalogue of studies: one folder per study (``study.toml``, its data, its README), the readers of each
mechanism kind (``kinds/``), the registry of kinds, the study-file loader (``catalogue.py``, ``study_file.py``) and
the multimodal test functions.  A new study is a folder here."""
