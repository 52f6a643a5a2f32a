"""The targets a GP is fitted to: simulated values, standardised, with a long upper tail compressed.

A minimiser only needs the model to rank and resolve the low values; values far above the median (Rosenbrock's
walls, a simulator's near-failures) would otherwise set the GP's signal variance and length-scales and flatten
everything that matters.  Both transforms below are monotone, so the ordering and every minimum are kept.

* A local model (the trust regions that continue a budget beyond the global model's size): above the median the
  values are mapped through log1p of their robust z-score, then the whole is standardised.
* A global model (the ``global`` plan) has to see the walls between basins, and that fixed compression flattened
  them.  Its values go through the Yeo-Johnson power transform whose exponent λ makes them most nearly Gaussian,
  as the GP assumes (maximum likelihood; HEBO's transform, Cowen-Rivers et al. 2022), only where the values reject
  λ = 1 (no transform) by a likelihood-ratio test at 5 % (χ²₁: 3.84): a long upper tail, Rosenbrock's walls, a
  squared error's decades.  λ is capped at 1: a power above 1 would compress the low tail, the few deep designs a
  minimiser has to resolve.  The test keeps the identity where the values do not ask for a transform: applied
  always, it cost the ventilator (the measurements: ``docs/guide/design-evidence.md``).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.stats import yeojohnson, yeojohnson_llf

__all__ = ["gaussianise", "standardise"]

#: Range searched for the Yeo-Johnson exponent of standardised values: 1 is the identity; the lower end is a stronger
#: compression than any log (λ = 0) and far beyond any fit seen.
_LAMBDA = (-3.0, 1.0)
#: 95 % point of χ² with one degree of freedom (3.841), the likelihood-ratio test of λ = 1.
_CHI2_1_95 = 3.84


def standardise(values: np.ndarray, compress_tail: bool = True) -> np.ndarray:
    """Monotone, standardised targets (mean 0, standard deviation 1) of finite values (n,).

    Parameters
    ----------
    values : (n,) ndarray
        Finite objective values.
    compress_tail : bool
        Compress the values above the median (a local model, which only has to rank the low values); False keeps
        the landscape's shape, which a global model needs to tell where the basins are.
    """
    v = np.asarray(values, dtype=float)
    if not compress_tail:
        v = gaussianise(v)
        sd = float(np.std(v))
        return (v - v.mean()) / (sd if sd > 0 else 1.0)
    med = float(np.median(v))
    q25, q75 = np.percentile(v, [25.0, 75.0])
    scale = (q75 - q25) / 1.349 or float(np.std(v)) or 1.0
    z = (v - med) / scale
    z = np.where(z > 0.0, np.log1p(np.maximum(z, 0.0)), z)
    sd = float(np.std(z))
    return (z - z.mean()) / (sd if sd > 0 else 1.0)


def gaussianise(values: np.ndarray) -> np.ndarray:
    """Values (n,) through the Yeo-Johnson transform of exponent λ <= 1 that makes them most nearly Gaussian, where
    a likelihood-ratio test rejects λ = 1 at 5 %; otherwise only centred and scaled.

    The values are first centred on their median and scaled by their standard deviation: the transform is not
    invariant to either, and the objective's units (N·m, mm, or a function's plain number) must not choose λ.

    Parameters
    ----------
    values : (n,) ndarray
        Finite objective values.

    Returns
    -------
    (n,) ndarray
        Transformed values in the same order (the values themselves when fewer than three, or all equal).
    """
    v = np.asarray(values, dtype=float)
    sd = float(np.std(v))
    if v.size < 3 or not sd > 0:
        return v.copy()
    z = (v - np.median(v)) / sd
    res = minimize_scalar(lambda lam: -yeojohnson_llf(lam, z), bounds=_LAMBDA, method="bounded")
    # Twice the log-likelihood gained over λ = 1: below χ²₁'s 95 % point the values do not call for a transform.
    if not np.isfinite(res.fun) or -2.0 * (yeojohnson_llf(1.0, z) + res.fun) < _CHI2_1_95:
        return z
    return yeojohnson(z, lmbda=float(res.x))
