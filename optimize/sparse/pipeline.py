"""The sparse pipeline end to end (paper 002, Algorithm 1 and Section 4), within a simulation budget.

1. **Global model**: lines planned over the feasible region (or the paper's Δ and origin), sampled through the
   resumable store, fitted with sums of exponentials and blended; its exhaustive search gives a candidate, which is
   simulated to confirm it.
2. **Refinement**, within what is left of the budget (:mod:`.refine`): trust-region steps on the model corrected
   by every simulation so far (:mod:`.trust_region`), then a constrained local search on the simulator, then, with
   what it left, steps at the minimum of the model corrected by every simulation of the run
   (:func:`.refine.corrected_steps`) until d + 1 in a row bring nothing better.
3. The best *simulated* design is the optimum; nothing is reported from the model alone.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mechopt.optimize.sparse.options import SparseOptions
from mechopt.optimize.sparse.refine import corrected_steps, model_steps, refine_locally
from mechopt.optimize.sparse.sampler import Sampler
from mechopt.optimize.sparse.space import ModelSpace
from mechopt.optimize.sparse.stage import Stage, build_stage

__all__ = ["MISTRUST", "PipelineResult", "model_step_budget", "run_pipeline"]

#: Relative disagreement between model and simulation at the model's candidate beyond which the model is not trusted
#: to have found the right basin (the ventilator's global model: 0.3 %; a false minimum of an overshooting blend on
#: the flexible slider-crank: 100 %).
MISTRUST = 0.10
#: With batches of designs, the share of what is left after the lines that the model steps may take; the local
#: search (its gradients in one round with their design) and the corrected steps get the rest.  Measured on
#: Hartmann-3 at budget 60, batches of 8, 10 seeds (median gap in % of the range; one at a time: 4.9): the steps
#: taking all of it 14.8 (they end on a side basin's slope), half 10.6, a quarter 0.048.
BATCH_MODEL_STEP_SHARE = 0.25


@dataclass
class PipelineResult:
    """Every stage, the best simulated design and the accounting."""

    stages: list[Stage]
    best: Stage
    n_simulations: int
    message: str

    @property
    def x(self) -> np.ndarray:
        """The optimal design."""
        return self.best.candidate

    @property
    def fun(self) -> float:
        """Its simulated objective."""
        return self.best.simulated


def run_pipeline(space: ModelSpace, options: SparseOptions, sampler: Sampler,
                 log: Callable[[str], None] = print) -> PipelineResult:
    """The global model and its candidate, then a constrained local refinement on the simulator.

    Parameters
    ----------
    space : ModelSpace
        The problem in the model's coordinates.
    options : SparseOptions
        Lines, samples, budget, refinement.
    sampler : Sampler
        The simulator through the store.
    log : callable
        Where progress lines go.
    """
    problem = space.problem
    used_before = len(sampler.designs)
    # The lines take at most their share of the budget: the confirmation and the refinement keep the rest.
    stage = build_stage("global", space, options, sampler, options.n_lines, options.samples_per_line,
                        options.search_points, paper=options.plan == "paper", max_samples=options.line_cap())
    log(f"  global model: {stage.n_samples} samples on {stage.plan.n_lines} lines (coverage {stage.coverage:.0%}), "
        f"orders {[int(o) for o in np.ravel(stage.model.orders)]}; candidate {problem.describe(stage.candidate)}, "
        f"model {stage.predicted:.6g}, simulated {stage.simulated:.6g}")
    stages, best = [stage], stage
    message = f"{_claim_text(stage, problem)}; no refinement"
    remaining = options.budget - (len(sampler.designs) - used_before)
    # Agreement at one point does not prove the candidate optimal, so the refinement always runs when there is
    # budget: first trust-region steps on the model corrected by every simulation (one simulation per step, from the
    # best simulated design), then, from where they stall, SLSQP with forward differences (d simulations a gradient).
    # When the model's claim at its own candidate is off by more than MISTRUST, the blend did not resolve the
    # landscape (it overshoots between lines and puts its minimum in a false basin): the best line sample, not the
    # candidate, is where the steps start.
    start, start_value = stage.candidate, stage.simulated
    samples = np.vstack(stage.line_designs)
    values = np.concatenate(stage.line_values)
    ok = np.isfinite(values) & space.feasible(samples)
    mistrusted = not np.isfinite(start_value) or stage.agreement > MISTRUST
    if mistrusted and ok.any() and (not np.isfinite(start_value) or values[ok].min() < start_value):
        start, start_value = samples[ok][np.argmin(values[ok])], float(values[ok].min())
        log(f"  the best line sample ({problem.describe(start)}, {start_value:.6g}) beats the model's candidate: "
            "the local search starts there")
    if options.refine and remaining > 0 and np.isfinite(start_value):
        # First the model steers (one simulation per step), then finite differences finish from where it stalled.
        stepped = model_steps(space, sampler, stage, model_step_budget(remaining, sampler.batch_size), options.seed)
        remaining -= stepped.n_samples
        stages.append(stepped)
        log(f"  model steps: {stepped.n_samples} simulations of trust-region steps on the corrected model; "
            f"{problem.describe(stepped.candidate)}, simulated {stepped.simulated:.6g}")
        if stepped.simulated < best.simulated or not np.isfinite(best.simulated):
            best = stepped
        if remaining > space.dim + 1:
            fd_step = options.fd_step if options.fd_step is not None else problem.fd_step
            refined = refine_locally(space, sampler, best.candidate, remaining, stage, fd_step)
            stages.append(refined)
            log(f"  refinement: {refined.n_samples} simulations of a constrained local search (SLSQP) from the "
                f"best design; {problem.describe(refined.candidate)}, simulated {refined.simulated:.6g}")
            if refined.simulated < best.simulated:
                best = refined
        remaining = options.budget - (len(sampler.designs) - used_before)
        if remaining > 0:
            # Finite differences stop where the simulator's noise hides the gradient, often with budget left; the
            # model corrected by every simulation of the run still sees the basin's bottom.
            tail = corrected_steps(space, sampler, stage, remaining, options.seed)
            stages.append(tail)
            log(f"  corrected steps: {tail.n_samples} simulations at the minimum of the model corrected by every "
                f"simulation; {problem.describe(tail.candidate)}, simulated {tail.simulated:.6g}")
            if tail.simulated < best.simulated:
                best = tail
        message = (f"{_claim_text(stage, problem)}; model steps and a local search on the simulator moved it from "
                   f"{stage.simulated:.6g} to {best.simulated:.6g}")
    elif options.refine:
        message = f"{_claim_text(stage, problem)}; no budget left to refine"
    return PipelineResult(stages=stages, best=best, n_simulations=len(sampler.designs) - used_before, message=message)


def model_step_budget(remaining: int, batch: int) -> int:
    """The model steps' share of what is left: all of it one at a time (they stop by themselves once their region
    has shrunk, after 8 to 17 simulations at a budget of 60); with batches, :data:`BATCH_MODEL_STEP_SHARE` of it
    and at least one round, since a round of steps at several radii nearly always improves and they would not
    stop.  Whole rounds: a round of fewer than ``batch`` designs takes as long as a full one."""
    if batch <= 1:
        return remaining
    return min(remaining, batch * max(1, math.ceil(BATCH_MODEL_STEP_SHARE * remaining / batch)))


def _claim_text(stage: Stage, problem) -> str:
    """The model against the simulation at its candidate, absolute (the objective's unit) and as a share of the
    range of the line samples: a percentage of a value near 0 says nothing."""
    unit = dict(problem.output_units).get(problem.objective, "")
    diff = abs(stage.simulated - stage.predicted)
    share = "" if not np.isfinite(stage.claim_error) else (
        f", {stage.claim_error:.2%} of the range {stage.sampled_range:.4g} of the line samples")
    return (f"at the model's candidate the model says {stage.predicted:.6g} and the simulation {stage.simulated:.6g}"
            f" (differ by {diff:.3g}{(' ' + unit) if unit else ''}{share})")
