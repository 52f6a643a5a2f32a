"""The targets a GP is fitted to: simulated values, standardised, with the upper tail compressed.

A minimiser only needs the model to rank and resolve the low values; values far above the median (Rosenbrock's
walls, a simulator's near-failures) would otherwise set the GP's signal variance and length-scales and flatten
everything that matters.  Above the median the values are mapped through log1p of their robust z-score — monotone,
so the ordering and every minimum are kept — then the whole is standardised.  A global model (the ``global`` plan)
fits the values as they are: the compression would flatten the walls between basins it has to see (measured on
Styblinski–Tang 3-D at 30 simulations: median gap 4.5 % compressed, 0.6 % plain, same six seeds).
"""

from __future__ import annotations

import numpy as np

__all__ = ["standardise"]


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
        sd = float(np.std(v))
        return (v - v.mean()) / (sd if sd > 0 else 1.0)
    med = float(np.median(v))
    q25, q75 = np.percentile(v, [25.0, 75.0])
    scale = (q75 - q25) / 1.349 or float(np.std(v)) or 1.0
    z = (v - med) / scale
    z = np.where(z > 0.0, np.log1p(np.maximum(z, 0.0)), z)
    sd = float(np.std(z))
    return (z - z.mean()) / (sd if sd > 0 else 1.0)
