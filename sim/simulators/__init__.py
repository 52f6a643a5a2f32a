"""Simulators in the loop: a user's external program or Python function evaluates the designs mechopt chooses.

A study file's ``[simulator]`` section replaces the evaluator of the mechanism plug-in (which still gives the
variables, bounds and constraint margins), or, with ``kind = "external"``, drives a simulator with no plug-in at all.
"""
