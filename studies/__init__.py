"""Workflow of mechopt: study definitions, sampling and storage, validation, plots and the command line."""
