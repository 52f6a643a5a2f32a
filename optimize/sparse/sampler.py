"""The methods' door to the simulator: designs in, objective values out, through the resumable store.

Every design is moved to its allowed design first (:meth:`~mechopt.optimize.allowed_designs.AllowedDesigns.snap`:
the grids, integers and catalogues of discrete variables), so the store keys, simulates and returns allowed designs
only, and two proposals that round alike are one simulation.
"""

from __future__ import annotations

import math
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
        #: Whether some variable is discrete (designs are snapped to the allowed ones).
        self.discrete = bool(problem.discrete.any())
        if retry_failed:
            # Once per run: a design that fails again and is asked for again later is not retried twice.
            store.forget_failed(self.fingerprint)
        #: Canonical keys of the distinct designs this run asked for (float noise below 1e-9 is one design).
        self.designs: set[str] = set()
        #: The same designs, by key, in the order first asked for.
        self.asked: dict[str, tuple[float, ...]] = {}
        self.n_computed = 0
        self.n_cached = 0
        self.n_waited = 0
        self.failures: dict[str, tuple[tuple[float, ...], str]] = {}
        #: Every design of this run and its objective (NaN when failed), by key: what later steps model.
        self.history: dict[str, tuple[tuple[float, ...], float]] = {}
        self.sampling_time_s = 0.0
        #: Rounds of simulations: calls that dispatched at least one design to the simulators.
        self.rounds = 0
        #: Waves: a round of n designs on w workers is ceil(n / w) of them (the simulation time, in simulations).
        self.waves = 0
        #: Seconds the simulators spent on the designs this run dispatched (their recorded wall times summed).
        self.busy_s = 0.0
        #: Watchers of the run (:mod:`mechopt.runs.run_watch`): ``watcher.record(record, cached)`` once per distinct
        #: design, as it arrives.
        self.watchers: list = []
        self._watched: set[str] = set()
        self._started = time.perf_counter()

    @property
    def batch_size(self) -> int:
        """Designs a method should propose at once: the executor's workers (local processes or the Dask cluster's
        worker threads), at least 1; 1 in-process."""
        return max(1, int(getattr(self.executor, "workers", 1) or 1))

    @property
    def executor_description(self) -> str:
        """What ran the simulations (processes, in-process, a Dask scheduler)."""
        return getattr(self.executor, "description", "") or "in-process"

    def allowed(self, designs: np.ndarray) -> np.ndarray:
        """Designs (n, d) moved to their allowed designs (unchanged when every variable is continuous)."""
        designs = np.atleast_2d(np.asarray(designs, dtype=float))
        # Not clipped: the line model samples beyond the box on purpose, and its samples there must stay apart.
        return self.problem.snap(designs, clip=False) if self.discrete else designs

    def records(self, designs: np.ndarray, desc: str, snap: bool = True) -> list[SampleRecord]:
        """The store's records of the allowed designs of designs (n, d), simulating those it lacks; ``snap=False``
        simulates the designs as given (a study's reference designs, e.g. a continuous optimum beside a grid's)."""
        designs = self.allowed(designs) if snap else np.atleast_2d(np.asarray(designs, dtype=float))
        asked = [tuple(map(float, d)) for d in designs]
        keys = [design_key(d) for d in asked]
        first_time = len(set(keys) - self.designs)
        t0 = time.perf_counter()
        res = sample_designs(asked, self.problem, self.store, fingerprint=self.fingerprint, executor=self.executor,
                             progress=self.progress, desc=desc, on_record=self._arrived if self.watchers else None)
        for record in res.records:  # found in the store: watched once the call is over
            self._arrived(record, cached=True)
        self.sampling_time_s += time.perf_counter() - t0
        if res.n_computed + res.n_waited > 0:
            self.rounds += 1
            self.waves += math.ceil((res.n_computed + res.n_waited) / self.batch_size)
            self.busy_s += res.compute_time_s
        # Counted once per distinct design of the run: a design asked again later is neither new nor reused.
        self.n_computed += res.n_computed
        self.n_waited += res.n_waited
        self.n_cached += max(0, first_time - res.n_computed - res.n_waited)
        for key, d, r in zip(keys, asked, res.records, strict=True):
            self.designs.add(key)
            self.asked.setdefault(key, d)
            if r.status == "failed":
                self.failures[key] = (d, r.error or "failed")
        return list(res.records)

    def _arrived(self, record: SampleRecord, cached: bool = False) -> None:
        if record.key in self._watched or not self.watchers:
            return
        self._watched.add(record.key)
        for watcher in self.watchers:
            watcher.record(record, cached)

    def __call__(self, designs: np.ndarray, desc: str) -> np.ndarray:
        """The objective at the allowed designs of designs (n, d); NaN where the simulation did not succeed."""
        designs = self.allowed(designs)
        records = self.records(designs, desc)
        # The first objective, as minimised (a maximised output negated); NaN where the simulation did not succeed.
        spec = self.problem.objective_spec
        values = np.array([spec.senses[0] * r.value(spec.names[0]) for r in records], dtype=float)
        for d, v in zip(designs, values, strict=True):
            design = tuple(map(float, d))
            self.history[design_key(design)] = (design, float(v))
        return values

    def residuals(self, designs: np.ndarray, desc: str) -> tuple[np.ndarray, list]:
        """The objective and the residual vector (None where the simulation did not succeed) at designs (n, d), for a
        problem that declares :attr:`~mechopt.optimize.problem.DesignProblem.residuals`."""
        values = self(designs, desc)
        records = self.records(designs, desc)  # found in the store: nothing is simulated twice
        return values, [self.problem.residual_vector(r.outputs) if np.isfinite(v) else None
                        for r, v in zip(records, values, strict=True)]

    def timing(self) -> dict:
        """Rounds, waiting and the method's own time since this sampler was made.

        ``rounds``: calls that dispatched designs to the simulators; ``waves``: those calls in simulations one
        after the other (a call of n designs on w workers is ceil(n / w) waves); ``waiting_s``: wall time inside
        the calls (the run waited for simulations); ``method_s``: the rest of the wall time (the method's own
        computing); ``idle_share``: the share of the workers' time (``batch_size`` × wall time) not spent
        simulating.
        """
        wall = time.perf_counter() - self._started
        capacity = self.batch_size * wall
        idle = 1.0 - self.busy_s / capacity if capacity > 0 else 0.0
        return {"rounds": self.rounds, "waves": self.waves, "workers": self.batch_size, "wall_s": wall,
                "waiting_s": self.sampling_time_s, "method_s": max(0.0, wall - self.sampling_time_s),
                "busy_s": self.busy_s, "idle_share": min(1.0, max(0.0, idle))}

    def summary(self) -> dict:
        """Counts for result.json and the final log line."""
        return {"distinct_designs": len(self.designs), "new": self.n_computed, "reused": self.n_cached,
                "waited_for_other_runs": self.n_waited, "failed": len(self.failures),
                "executor": self.executor_description, **self.timing()}
