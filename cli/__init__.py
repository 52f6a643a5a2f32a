"""The ``mechopt`` command line: ``main.py`` parses and dispatches to one module per command, each of which parses
its arguments, calls the library (:mod:`mechopt.studies.runner`, :mod:`mechopt.studies.comparison`) and prints."""
