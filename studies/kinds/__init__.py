"""Study-file readers, one per mechanism kind: the ``kind`` of a study.toml names the file here that turns its
sections into a :class:`~mechopt.optimize.problem.DesignProblem` (see :mod:`mechopt.studies.registry`).  A new
mechanism is a folder in ``sim/`` and one reader here."""
