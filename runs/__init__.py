"""The run infrastructure: where simulations run and where their results are kept.

``store.py`` (the resumable SQLite store of simulated designs, shared by concurrent runs), ``sampling.py``
(evaluate many designs in parallel, reusing the store), ``executors.py`` (in-process, local processes, Dask),
``fingerprint.py`` (one hash of every setting that changes a simulated output).  Nothing here knows a method or a
mechanism.
"""
