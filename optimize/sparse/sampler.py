"""The pipeline's door to the simulator: designs in, objective values out, through the resumable store."""

from __future__ import annotations

import time

import numpy as np

from mechopt.optimize.problem import DesignProblem
from mechopt.runs.sampling import sample_designs
from mechopt.runs.store import SampleRecord, SampleStore, design_key

__all__ = ["Sampler"]


class Sampler:
    """Simulate designs through the store and count what was reused, simulated, failed or waited for.

    Parameters
    ----------
    problem : DesignProblem
        The problem (its evaluator runs in the executor's workers).
    store : SampleStore
        Where samples are looked up and committed.
    executor : SampleExecutor, optional
        Processes or a Dask cluster; default: every core.
    progress : bool
        Progress bars with rate and ETA.
    retry_failed : bool
        Simulate again the designs whose earlier simulation failed.
    """

    def __init__(self, problem: DesignProblem, store: SampleStore, executor=None, progress: bool = True,
                 retry_failed: bool = False) -> None:
        self.problem = problem
        self.store = store
        self.executor = executor
        self.progress = progress
        self.retry_failed = retry_failed
        self.fingerprint = problem.fingerprint()
        if retry_failed:
            # Once per run: a design that fails again and is asked for again later is not retried twice.
            store.forget_failed(self.fingerprint)
        #: Canonical keys of the distinct designs this run asked for (float noise below 1e-9 is one design).
        self.designs: set[str] = set()
        self.n_computed = 0
        self.n_cached = 0
        self.n_waited = 0
        self.failures: dict[str, tuple[tuple[float, ...], str]] = {}
        #: Every design of this run and its objective (NaN when failed), by key: what later steps model.
        self.history: dict[str, tuple[tuple[float, ...], float]] = {}
        self.sampling_time_s = 0.0

    @property
    def executor_description(self) -> str:
        """What ran the simulations (processes, in-process, a Dask scheduler)."""
        return getattr(self.executor, "description", "") or "in-process"

    def records(self, designs: np.ndarray, desc: str) -> list[SampleRecord]:
        """The store's records of designs (n, d), simulating those it lacks."""
        designs = np.atleast_2d(np.asarray(designs, dtype=float))
        asked = [tuple(map(float, d)) for d in designs]
        keys = [design_key(d) for d in asked]
        first_time = len(set(keys) - self.designs)
        t0 = time.perf_counter()
        res = sample_designs(asked, self.problem, self.store, fingerprint=self.fingerprint, executor=self.executor,
                             progress=self.progress, desc=desc)
        self.sampling_time_s += time.perf_counter() - t0
        # Counted once per distinct design of the run: a design asked again later is neither new nor reused.
        self.n_computed += res.n_computed
        self.n_waited += res.n_waited
        self.n_cached += max(0, first_time - res.n_computed - res.n_waited)
        for key, d, r in zip(keys, asked, res.records, strict=True):
            self.designs.add(key)
            if r.status == "failed":
                self.failures[key] = (d, r.error or "failed")
        return list(res.records)

    def __call__(self, designs: np.ndarray, desc: str) -> np.ndarray:
        """The objective at designs (n, d); NaN where the simulation did not succeed."""
        records = self.records(designs, desc)
        name = self.problem.objective
        values = np.array([r.value(name) for r in records], dtype=float)
        for d, v in zip(np.atleast_2d(np.asarray(designs, dtype=float)), values, strict=True):
            design = tuple(map(float, d))
            self.history[design_key(design)] = (design, float(v))
        return values

    def summary(self) -> dict:
        """Counts for result.json and the final log line."""
        return {"distinct_designs": len(self.designs), "new": self.n_computed, "reused": self.n_cached,
                "waited_for_other_runs": self.n_waited, "failed": len(self.failures),
                "executor": self.executor_description}
