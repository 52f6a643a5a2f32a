"""BoTorch's qLogNoisyExpectedImprovement in BoTorch's own loop (Ament et al. 2023, "Unexpected improvements to
expected improvement"), a budget-limited baseline for one objective.

The loop of BoTorch's closed-loop tutorial ("Closed-loop batch, constrained BO in BoTorch with qEI and qNEI"), one
design per step: a scrambled Sobol start of 2 (d + 1) designs in the unit cube of the box; then at every step one
``SingleTaskGP`` per modelled output (BoTorch's defaults: Matérn-5/2 with one length-scale per variable and its
priors, a ``Standardize`` outcome transform) fitted by ``fit_gpytorch_mll``, ``qLogNoisyExpectedImprovement``
on the baseline of every design simulated (``prune_baseline=True``, 128 quasi-Monte-Carlo samples) and
``optimize_acqf`` with the tutorial's 10 restarts from 512 raw samples.  PyTorch runs on one thread (the machine's
cores are shared by the runs).

Constraint handling: the tutorial's.  Each margin is a modelled output, and the acquisition weights the improvement
by the probability that every margin is met (``constraints``, a smooth sigmoid of the sampled margin).  The margins
are known for every proposal, simulated or not; an infeasible proposal is not simulated and its objective is
:func:`~optimize.baselines.library.rejected_value` (above every simulated value).  A failed simulation gets the same
value.  A proposal already simulated (the acquisition's optimiser can return the incumbent) is replaced by a fresh
feasible random design, so every step spends a simulation.  Needs the ``gp-peers`` extra.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult

from mechopt.optimize.baselines.library import GP_PEERS_HINT, rejected_value, require
from mechopt.optimize.baselines.torch_threads import one_torch_thread
from mechopt.optimize.budget import BudgetExhausted, CountedProblem

__all__ = ["minimize_botorch_qlognei"]


def _observe(problem: CountedProblem, u: np.ndarray) -> tuple[np.ndarray, bool]:
    """Outputs of a unit-cube design: (−objective, margins...) maximised / >= 0, and whether it was simulated."""
    x = problem.from_unit(u)
    # A margin the constraint function could not give (NaN) counts as violated.
    margins = np.nan_to_num(np.asarray(problem.margins(x), dtype=float).ravel(), nan=-1.0)
    if problem.feasible(x)[0]:
        f = problem.evaluate(x)
        simulated = True
    else:
        problem.penalised(x)  # counts the proposal, never simulates
        f, simulated = math.nan, False
    if not math.isfinite(f):
        f = rejected_value(problem, x)
    return np.concatenate([[-f], margins]), simulated


def _candidate(torch: Any, U: np.ndarray, Y: np.ndarray, seed: int, num_restarts: int, raw_samples: int) -> np.ndarray:
    """The maximiser of qLogNEI given the designs U (n, d) and outputs Y (n, 1 + m), in the unit cube."""
    from botorch.acquisition.logei import qLogNoisyExpectedImprovement
    from botorch.acquisition.objective import GenericMCObjective
    from botorch.fit import fit_gpytorch_mll
    from botorch.models import ModelListGP, SingleTaskGP
    from botorch.models.transforms import Standardize
    from botorch.optim import optimize_acqf
    from botorch.sampling import SobolQMCNormalSampler
    from gpytorch.mlls import ExactMarginalLogLikelihood, SumMarginalLogLikelihood

    X_t, Y_t = torch.tensor(U, dtype=torch.double), torch.tensor(Y, dtype=torch.double)
    models = [SingleTaskGP(X_t, Y_t[:, i: i + 1], outcome_transform=Standardize(m=1)) for i in range(Y.shape[1])]
    if len(models) == 1:
        model = models[0]
        fit_gpytorch_mll(ExactMarginalLogLikelihood(model.likelihood, model))
        objective, constraints = None, None
    else:
        model = ModelListGP(*models)
        fit_gpytorch_mll(SumMarginalLogLikelihood(model.likelihood, model))
        objective = GenericMCObjective(lambda Z, X=None: Z[..., 0])
        # BoTorch's convention: a constraint is met where the callable is <= 0, so the margin's negative.
        constraints = [(lambda Z, j=j: -Z[..., j]) for j in range(1, Y.shape[1])]
    acq = qLogNoisyExpectedImprovement(model=model, X_baseline=X_t, prune_baseline=True, objective=objective,
                                       constraints=constraints,
                                       sampler=SobolQMCNormalSampler(sample_shape=torch.Size([128]), seed=seed))
    unit = torch.stack([torch.zeros(U.shape[1]), torch.ones(U.shape[1])]).double()
    cand, _ = optimize_acqf(acq, bounds=unit, q=1, num_restarts=num_restarts, raw_samples=raw_samples)
    return np.clip(cand.detach().numpy()[0], 0.0, 1.0)


def minimize_botorch_qlognei(
    problem: CountedProblem,
    seed: int,
    *,
    n_initial: int | None = None,
    num_restarts: int = 10,
    raw_samples: int = 512,
) -> OptimizeResult:
    """BoTorch's qLogNEI loop until the budget is spent.

    Parameters
    ----------
    problem : CountedProblem
    seed : int
        Seed of the Sobol start, of PyTorch and of the quasi-Monte-Carlo samples.
    n_initial : int, optional
        Designs of the Sobol start, default 2 (d + 1) (BoTorch's tutorials).
    num_restarts : int, default 10
        Starts of the acquisition's optimiser (the tutorial's).
    raw_samples : int, default 512
        Random designs from which those starts are chosen (the tutorial's).

    Returns
    -------
    scipy.optimize.OptimizeResult
        Best feasible simulated design (``x``, ``fun``), ``nfev``, ``success``, ``message``, ``nsteps`` (model
        steps), ``nreplaced`` (repeated proposals replaced by a random design).
    """
    torch = require("torch", "botorch_qlognei", GP_PEERS_HINT)
    require("botorch", "botorch_qlognei", GP_PEERS_HINT)
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    d = problem.dim
    message, steps, replaced = "budget spent", 0, 0
    # BoTorch's draw_sobol_samples: PyTorch's scrambled Sobol engine.
    U = torch.quasirandom.SobolEngine(d, scramble=True, seed=seed).draw(n_initial or 2 * (d + 1)).double().numpy()
    rows: list[np.ndarray] = []
    with one_torch_thread():
        try:
            for u in U:
                rows.append(_observe(problem, u)[0])
            while problem.remaining > 0:
                u = _candidate(torch, U, np.array(rows), seed + steps, num_restarts, raw_samples)
                steps += 1
                if np.min(np.max(np.abs(U - u), axis=1)) < 1e-9:
                    replaced += 1
                    fresh = problem.sample_feasible(1, rng)
                    u = problem.to_unit(fresh[0]) if fresh.shape[0] else rng.random(d)
                y, _ = _observe(problem, u)
                U, rows = np.vstack([U, u]), [*rows, y]
        except BudgetExhausted as exc:
            message = str(exc)
    return problem.result(message, nsteps=steps, nreplaced=replaced)
