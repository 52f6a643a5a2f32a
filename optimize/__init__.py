"""The optimizer: the design-problem protocol, :func:`mechopt.minimize` and its methods.

``problem.py`` (what a method needs of a problem), ``methods.py`` (the table of methods: one record per method,
with what it takes and its declared options), ``minimize.py`` (one entry point, dispatching through the table),
``method_runs.py`` (how each kind of method runs on the sampler), ``result.py`` (the one result type),
``options.py`` (declared options), ``budget.py`` (the simulation budget every baseline is held to),
``ground_truth.py`` (a problem's true optimum by brute force); one folder or file per method: ``sparse/`` (paper
002's pipeline), ``sparse_global.py``, ``baselines/`` (the literature's and the maintained libraries' optimizers).
A new method is a function there and one record in ``methods.py``.
"""
