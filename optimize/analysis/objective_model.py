"""A model of the objective from designs already simulated: the Gaussian process of the default method, fitted to the
designs of a sample store (or a run) nearest to where it is asked.

The analyses of a result (tolerances, robust optimum, sensitivity) evaluate the objective at thousands of scattered
designs; they read a model instead of the simulator.  The model is :class:`mechopt.optimize.auto.gp.GaussianProcess`
on the unit cube of the problem's box, fitted by maximum marginal likelihood to the ``nearest`` stored designs
(all of them for a global model), with linearly standardised values so that predictions map back to the
objective's unit exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechopt.errors import InputError
from mechopt.optimize.problem import DesignProblem
from mechopt.runs.store import SampleStore

__all__ = ["ObjectiveGP", "fit_objective_model", "stored_designs"]


@dataclass(frozen=True)
class ObjectiveGP:
    """A fitted model of the objective.

    Attributes
    ----------
    gp : GaussianProcess
        The fit on the unit cube of ``bounds`` with standardised values.
    bounds : (d, 2) ndarray
        The box the unit cube maps to, in the variables' units.
    level, scale : float
        The values' mean and standard deviation (objective unit).
    n : int
        Designs the model was fitted to.
    """

    gp: object
    bounds: np.ndarray
    level: float
    scale: float
    n: int

    def predict(self, X: np.ndarray, std: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """Predicted objective (m,) at designs X (m, d) in the variables' units; with ``std`` also its standard
        deviation."""
        U = (np.atleast_2d(X) - self.bounds[:, 0]) / (self.bounds[:, 1] - self.bounds[:, 0])
        out = np.empty(U.shape[0])
        sd = np.empty(U.shape[0])
        for i in range(0, U.shape[0], 4096):  # the cross-covariance of a chunk stays a few MB
            m, s = self.gp.predict(U[i:i + 4096])
            out[i:i + 4096], sd[i:i + 4096] = m, s
        mean = self.level + self.scale * out
        return (mean, self.scale * sd) if std else mean


def stored_designs(problem: DesignProblem, store: SampleStore | None) -> tuple[np.ndarray, np.ndarray]:
    """Designs (n, d) of ``problem`` simulated successfully in ``store``, with their objective (n,)."""
    if store is None:
        return np.empty((0, problem.dim)), np.empty(0)
    rows = [(r.design, r.outputs.get(problem.objective)) for r in store.records(problem.fingerprint(), status="ok")]
    rows = [(d, v) for d, v in rows if isinstance(v, int | float) and np.isfinite(v)]
    if not rows:
        return np.empty((0, problem.dim)), np.empty(0)
    return np.array([d for d, _ in rows], dtype=float), np.array([v for _, v in rows], dtype=float)


def fit_objective_model(problem: DesignProblem, X: np.ndarray, y: np.ndarray, centre: np.ndarray | None = None,
                        nearest: int = 80, seed: int = 0) -> ObjectiveGP:
    """Fit the objective's model to simulated designs.

    Parameters
    ----------
    problem : DesignProblem
        Its box sets the unit cube.
    X : (n, d) ndarray
        Simulated designs, in the variables' units.
    y : (n,) ndarray
        Their objective.
    centre : (d,) ndarray, optional
        Fit to the ``nearest`` designs to this one (a local model); None: to all (a global model).
    nearest : int
        Designs of a local model.
    seed : int
        Seed of the fit's random starts.

    Raises
    ------
    InputError
        Fewer than d + 2 designs.
    """
    from mechopt.optimize.auto.gp import fit_gp

    X, y = np.asarray(X, dtype=float), np.asarray(y, dtype=float)
    if X.shape[0] < problem.dim + 2:
        raise InputError(f"{X.shape[0]} simulated designs of {problem.name!r}: the model of the objective needs at "
                         f"least {problem.dim + 2}")
    b = problem.bounds
    U = (X - b[:, 0]) / (b[:, 1] - b[:, 0])
    if centre is not None and X.shape[0] > nearest:
        c = (np.asarray(centre, dtype=float) - b[:, 0]) / (b[:, 1] - b[:, 0])
        keep = np.argsort(np.linalg.norm(U - c, axis=1))[:nearest]
        U, y = U[keep], y[keep]
    # Designs stored twice (float noise below the store's resolution) would make the covariance singular.
    U, first = np.unique(np.round(U, 12), axis=0, return_index=True)
    y = y[first]
    level, scale = float(np.mean(y)), float(np.std(y)) or 1.0
    gp = fit_gp(U, (y - level) / scale, np.random.default_rng(seed), starts=3, prior=False)
    return ObjectiveGP(gp=gp, bounds=b, level=level, scale=scale, n=int(U.shape[0]))
