"""The one result type of :func:`mechopt.minimize`, whatever the method (scipy's ``OptimizeResult`` convention)."""

from __future__ import annotations

from scipy.optimize import OptimizeResult as _ScipyResult

__all__ = ["OptimizeResult"]


class OptimizeResult(_ScipyResult):
    """Result of :func:`mechopt.minimize`: a dict with attribute access, as scipy's.

    Attributes
    ----------
    x : (d,) ndarray
        The best feasible design simulated, in the variables' units.
    fun : float
        Its simulated objective.
    outputs : dict
        Every output of the evaluator at ``x``.
    nfev : int
        Simulator calls the method used (distinct designs; what the budget counts).
    nnew, nreused, nfailed : int
        Of the designs the run asked for: simulated now, found in the store, failed.
    success : bool
        A feasible design was simulated.
    message : str
        One line on how the method ended.
    method : str
        ``"sparse"`` or a baseline's name.
    model : ObjectiveModel or None
        The global sparse model (sparse method).
    stages : list
        The pipeline's stages (sparse method).
    validation : Validation or None
        Held-out lines against the model (sparse method, when asked for).
    trust : dict
        Whether the line model resolves the landscape, and where the answer came from (``verdict``: one
        sentence; studies and ``"sparse-global"``; :func:`mechopt.optimize.sparse.model_confidence.study_trust`).
    sampling : dict
        Counts, the executor used and the timing of :meth:`mechopt.optimize.sparse.sampler.Sampler.timing`.
    rounds : int
        Rounds of simulations: calls that dispatched designs to the simulators (at most ``batch_size`` at once run
        together; the optimum's final look-up included, free when it was simulated before).
    batch_size : int
        Designs the method could propose at once: the workers (local processes or the Dask cluster's threads).
    idle_share : float
        Share of the workers' time (``batch_size`` × the run's wall time) not spent simulating.
    waiting_s : float
        Seconds the method waited for simulations (inside the sampler's calls).
    method_s : float
        Seconds of the method's own computing: the wall time of the run minus ``waiting_s``.
    wall_time_s : float
        Wall time of the call.

    With several objectives (:mod:`mechopt.optimize.objectives`), ``x`` is (n, d) and ``fun`` (n, k): the
    non-dominated simulated designs that meet every margin and limit, sorted by the first objective, each objective
    as minimised (a maximised output negated); ``front_outputs`` holds every output of each, ``hypervolume`` the
    hypervolume of the normalised front, ``reference_point`` its reference in objective units, ``normalisation``
    the normalisation in one sentence and ``hypervolume_trace`` the hypervolume after each simulation
    (:mod:`mechopt.optimize.pareto`).  With limits, ``feasible`` marks each returned design; a run where no design
    meets them has ``success`` False and returns the designs that come closest.  ``simulated`` holds every design
    of the run (``X``, ``F``, ``G``, ``ok``, ``feasible``).
    """
