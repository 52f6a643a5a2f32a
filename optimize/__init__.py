"""The optimizer: the design-problem protocol, :func:`mechopt.minimize` and its methods.

``problem.py`` (what a method needs of a problem), ``minimize.py`` (one entry point, dispatching by name to a
method), ``result.py`` (the one result type), ``options.py`` (declared options), ``budget.py`` (the simulation
budget every baseline is held to), ``ground_truth.py`` (a problem's true optimum by brute force); one folder or file
per method: ``sparse/`` (paper 002's pipeline), ``sparse_global.py``, ``baselines/`` (the literature's and the
maintained libraries' optimizers).  A new method is a file here and one entry in ``minimize.METHODS``.
"""
