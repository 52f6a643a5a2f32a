"""What every Exudyn engine of mechopt shares: the solver settings of a run sampled at fixed instants, and a
sensor's stored values read back on those instants."""

from __future__ import annotations

import numpy as np

from mechopt.errors import MechoptError

__all__ = ["sampled", "solver_settings"]


def solver_settings(exu, t_end: float, n_samples: int, steps_per_sample: int, newton_tolerance: float):
    """Generalized-α over [0, t_end] s, sensors stored once per sample, no file and no console output.

    Parameters
    ----------
    exu : module
        The ``exudyn`` module.
    t_end : float
        End time (s).
    n_samples : int
        Sample instants, t = 0 included.
    steps_per_sample : int
        Time steps between two samples.
    newton_tolerance : float
        Newton's relative tolerance (loose for ANCF links).
    """
    settings = exu.SimulationSettings()
    settings.timeIntegration.endTime = t_end
    settings.timeIntegration.numberOfSteps = steps_per_sample * (n_samples - 1)
    settings.timeIntegration.newton.relativeTolerance = newton_tolerance
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = t_end / (n_samples - 1)
    settings.solution.file.writeInitialValues = True
    settings.show.computationTime = False
    settings.show.statistics = False
    return settings


def sampled(mbs, sensor: int, t_end: float, n_samples: int,
            error: type[Exception] = MechoptError) -> np.ndarray:
    """A sensor's stored values on the ``n_samples`` instants over [0, t_end] s, shape (n_samples, n_values).

    Raises
    ------
    error
        When Exudyn stored fewer rows than sample instants.
    """
    dt_out = t_end / (n_samples - 1)
    data = np.asarray(mbs.GetSensorStoredData(sensor))
    # one row per write period; match rows to the sample instants by time (the first row is t = 0)
    idx = np.rint(data[:, 0] / dt_out).astype(int)
    ok = (idx >= 0) & (idx < n_samples) & (np.abs(data[:, 0] - idx * dt_out) < 1e-3 * dt_out)
    values = np.full((n_samples, data.shape[1] - 1), np.nan)
    values[idx[ok]] = data[ok, 1:]
    stored = len(np.unique(idx[ok]))
    if stored < n_samples:
        raise error(f"Exudyn stored {stored} of {n_samples} samples")
    return values
