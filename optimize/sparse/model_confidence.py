"""The trust report of a study: can the line model resolve this landscape, and where did the answer come from?

The pipeline always answers with its best *simulated* design, so a wrong model never gives a wrong number; but a
model that cannot resolve the landscape (features narrower than its line spacing, several basins) can send the local
search to the wrong basin, and a user should hear that in the report rather than read a confident optimum.  Three
measures, each a fraction of a range so that one threshold serves every study:

* leave-one-line-out: each line's samples predicted by the blend of the other lines (:mod:`surrogate.line_error`),
  RMS over the line, relative to the range of all line samples (of the fitted quantity: T_RMS² where the study fits
  the square);
* the model's claim: model against simulation at the model's own candidate, relative to the range of the line
  samples (relative to the simulated value it would mean nothing for an objective whose best value is near 0);
* held-out validation, when it ran: RMSE relative to the range of the held-out values.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mechopt.optimize.sparse.stage import Stage
from mechopt.optimize.sparse.validate import Validation
from mechopt.surrogate import SurrogateError
from mechopt.surrogate.line_error import leave_one_line_out

__all__ = ["REMEDY", "RESOLVED", "study_trust"]

#: Largest relative error (of each measure) at which the model is said to resolve the landscape.
RESOLVED = 0.05

#: What a user can do about an unresolved landscape, named as the command-line flag and the API argument.
REMEDY = ("Remedies: more lines (mechopt study --lines-fit N, or mechopt.minimize(options={'n_lines': N}) with a "
          "budget that pays for them), or the global method (mechopt study --method sparse-global, or "
          "mechopt.minimize(method='sparse-global'))")


def study_trust(global_stage: Stage, final: Stage, validation: Validation | None = None) -> dict[str, Any]:
    """Measures of the global model's trustworthiness and a one-sentence verdict.

    Parameters
    ----------
    global_stage : Stage
        The global model's stage (its lines, their samples and its candidate).
    final : Stage
        The stage whose design is the answer.
    validation : Validation, optional
        Held-out validation of the global model.

    Returns
    -------
    dict
        ``lolo_median``, ``lolo_max`` (fractions of the sampled range), ``claim_error`` (fraction of the line samples'
        range), ``heldout_error`` (fraction of the held-out range; each None when it could not be measured, e.g.
        without validation), ``resolved`` (bool),
        ``source`` (the answering stage) and ``verdict`` (one sentence).
    """
    model = global_stage.model
    values = [np.asarray(v, dtype=float) for v in global_stage.line_values]
    fitted = [v * v for v in values] if model.fit == "square" else values
    lolo_median = lolo_max = math.nan
    try:
        lolo = leave_one_line_out(model.model, fitted)
        lolo_median, lolo_max = lolo.median, lolo.max
    except SurrogateError:
        pass  # fewer than 3 lines, or lines cut by failed samples: no estimate, said as NaN
    claim = global_stage.claim_error
    heldout = math.nan
    if validation is not None and math.isfinite(validation.rmse_pct_of_range):
        heldout = validation.rmse_pct_of_range / 100.0
    measured = [m for m in (lolo_median, claim, heldout) if math.isfinite(m)]
    resolved = bool(measured) and max(measured) <= RESOLVED
    parts = [f"leave-one-line-out error {_pct(lolo_median)} of the sampled range",
             f"its claim at its candidate off by {_pct(claim)} of that range"]
    if math.isfinite(heldout):
        parts.append(f"held-out error {_pct(heldout)} of the held-out range")
    where = f"the answer is the best simulated design, from the stage '{final.name}'"
    if resolved:
        verdict = f"the global model resolves the landscape ({', '.join(parts)}); {where}"
    else:
        verdict = (f"the global model does not resolve the landscape at this line spacing ({', '.join(parts)}): it "
                   f"only pointed at a basin, and another basin may be lower; {where}. {REMEDY}")
    # None, not NaN, for a measure that could not be taken: result.json stays valid JSON.
    return {"lolo_median": _or_none(lolo_median), "lolo_max": _or_none(lolo_max), "claim_error": _or_none(claim),
            "heldout_error": _or_none(heldout), "resolved": resolved, "source": final.name, "verdict": verdict}


def _or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _pct(value: float) -> str:
    return "n/a" if not math.isfinite(value) else f"{value:.1%}"
