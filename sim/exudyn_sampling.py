"""What every Exudyn engine of mechopt shares: the solver settings of a run sampled at fixed instants, a
sensor's stored values read back on those instants, and the rigid crank turned at a constant rate that drives the
flexible linkages."""

from __future__ import annotations

import numpy as np

from mechopt.errors import MechoptError

__all__ = ["add_driven_crank", "sampled", "solver_settings"]


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


def add_driven_crank(mbs, items, length: float, omega: float, ground: int, m_ground_coord: int) -> int:
    """A rigid crank pinned at the origin and turned at the constant rate ``omega``; returns the marker of its tip.

    Parameters
    ----------
    mbs, items : Exudyn system and its ``itemInterface`` module.
    length : float
        Crank length (m).
    omega : float
        Prescribed rate (rad/s), counter-clockwise; the crank starts along +x.
    ground : int
        The ground body.
    m_ground_coord : int
        A ground coordinate marker (the rate constraint's reference).
    """
    # its inertia is irrelevant (the rate is prescribed), a small one keeps the mass matrix regular
    crank_mass = 1e-3
    n_crank = mbs.AddNode(items.NodeRigidBody2D(referenceCoordinates=[0.0, 0.0, 0.0],
                                                initialVelocities=[0.0, 0.0, omega]))
    o_crank = mbs.AddObject(items.ObjectRigidBody2D(mass=crank_mass, inertia=crank_mass * length * length / 3.0,
                                                    nodeNumber=n_crank))
    m_o_ground = mbs.AddMarker(items.MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    m_o_crank = mbs.AddMarker(items.MarkerBodyRigid(bodyNumber=o_crank, localPosition=[0.0, 0.0, 0.0]))
    mbs.AddObject(items.RevoluteJoint2D(markerNumbers=[m_o_ground, m_o_crank]))
    m_crank_angle = mbs.AddMarker(items.MarkerNodeCoordinate(nodeNumber=n_crank, coordinate=2))
    mbs.AddObject(items.CoordinateConstraint(markerNumbers=[m_ground_coord, m_crank_angle], offset=omega,
                                             velocityLevel=True))
    return mbs.AddMarker(items.MarkerBodyRigid(bodyNumber=o_crank, localPosition=[length, 0.0, 0.0]))
