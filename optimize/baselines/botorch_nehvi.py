"""BoTorch's qLogNEHVI loop (a peer of :mod:`~mechopt.optimize.baselines.multi_objective_peers`), as in BoTorch's
constrained multi-objective tutorial: one ``SingleTaskGP`` per objective and per constraint on the unit cube,
fitted by ``fit_gpytorch_mll``, and ``optimize_acqf`` over the cube, one design per step.

The reference point is the problem's (its ``nadir`` + 10 % of the front's range, the benchmark's) when it declares
``ideal`` and ``nadir``; otherwise the worst value simulated of each objective.
"""

from __future__ import annotations

import numpy as np

from mechopt.optimize.baselines.torch_threads import one_torch_thread

__all__ = ["run_qlognehvi"]


def _reference(counted, Y: np.ndarray) -> np.ndarray:  # noqa: ANN001 - multi_objective_peers._Counted
    """Reference point of the maximised objectives −f."""
    problem = counted.problem
    ideal, nadir = getattr(problem, "ideal", None), getattr(problem, "nadir", None)
    if ideal is not None and nadir is not None:
        return -(np.asarray(nadir) + 0.1 * (np.asarray(nadir) - np.asarray(ideal)))
    return Y.min(axis=0)


def run_qlognehvi(counted, bounds: np.ndarray, budget: int, seed: int) -> None:  # noqa: ANN001
    """Spend ``budget`` evaluations of ``counted`` (records every call itself).

    Parameters
    ----------
    counted : multi_objective_peers._Counted
        The problem's recorded evaluator: ``counted(x) -> (f (k,), constraint values (c,) <= 0 feasible)``.
    bounds : (d, 2) ndarray
        The variables' bounds.
    budget : int
        Evaluations.
    seed : int
        Seed of the Sobol start and of the optimiser's restarts.
    """
    import torch

    torch.manual_seed(seed)
    with one_torch_thread():
        _loop(counted, bounds, budget, seed)


def _loop(counted, bounds: np.ndarray, budget: int, seed: int) -> None:  # noqa: ANN001
    import torch
    from botorch.acquisition.multi_objective.logei import qLogNoisyExpectedHypervolumeImprovement
    from botorch.acquisition.multi_objective.objective import IdentityMCMultiOutputObjective
    from botorch.fit import fit_gpytorch_mll
    from botorch.models import ModelListGP, SingleTaskGP
    from botorch.models.transforms import Standardize
    from botorch.optim import optimize_acqf
    from botorch.sampling import SobolQMCNormalSampler
    from gpytorch.mlls import SumMarginalLogLikelihood
    from scipy.stats import qmc

    d, k, c = bounds.shape[0], counted.spec.k, counted.n_constraints
    lo, width = bounds[:, 0], bounds[:, 1] - bounds[:, 0]
    U = qmc.Sobol(d, seed=seed).random(min(budget, 2 * (d + 1)))
    rows = [counted(lo + u * width) for u in U]
    Y = [np.concatenate([-f, cv]) for f, cv in rows]
    unit = torch.stack([torch.zeros(d), torch.ones(d)]).double()
    while len(Y) < budget:
        X_t = torch.tensor(U, dtype=torch.double)
        Y_t = torch.tensor(np.array(Y), dtype=torch.double)
        models = [SingleTaskGP(X_t, Y_t[:, i: i + 1], outcome_transform=Standardize(m=1)) for i in range(k + c)]
        model = ModelListGP(*models)
        fit_gpytorch_mll(SumMarginalLogLikelihood(model.likelihood, model))
        ref = torch.tensor(_reference(counted, np.array(Y)[:, :k]), dtype=torch.double)
        acq = qLogNoisyExpectedHypervolumeImprovement(
            model=model, ref_point=ref, X_baseline=X_t, prune_baseline=True,
            objective=IdentityMCMultiOutputObjective(outcomes=list(range(k))),
            constraints=[(lambda Z, j=j: Z[..., k + j]) for j in range(c)] or None,
            sampler=SobolQMCNormalSampler(sample_shape=torch.Size([64]), seed=seed + len(Y)))
        cand, _ = optimize_acqf(acq, bounds=unit, q=1, num_restarts=4, raw_samples=128,
                                options={"batch_limit": 5, "maxiter": 100})
        u = cand.detach().numpy()[0]
        f, cv = counted(lo + u * width)
        U = np.vstack([U, u])
        Y.append(np.concatenate([-f, cv]))
