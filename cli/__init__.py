"""The ``mechopt`` command line: ``main.py`` parses and dispatches, ``run_study.py`` runs a whole study,
``compare.py`` runs optimizers side by side at equal budgets."""
