"""Valleys: ill-conditioned, curved and ridged test functions, rotated and shifted, at 3, 6 and 10 variables.

Each is one of the unimodal functions of the COCO/BBOB noiseless suite (N. Hansen, S. Finck, R. Ros, A. Auger,
"Real-Parameter Black-Box Optimization Benchmarking 2009: Noiseless Functions Definitions", INRIA RR-6829, 2009;
the function numbers below are theirs) on the box [−5, 5]^d:

- f10, the ellipsoid Σ 10^(6 (i−1)/(d−1)) z_i² with z = R (x − x*): condition 10^6;
- f12, the bent cigar z_1² + 10^6 Σ_{i>=2} z_i² with z = R T_asy^0.5(R (x − x*));
- f9, Rosenbrock Σ 100 (z_i² − z_{i+1})² + (z_i − 1)² with z = max(1, √d / 8) R (x − x*) + 1;
- f13, the sharp ridge z_1² + 100 √(Σ_{i>=2} z_i²) with z = Q Λ^10 R (x − x*);
- f14, the sum of different powers √(Σ |z_i|^(2 + 4 (i−1)/(d−1))) with z = R (x − x*).

R and Q are random orthogonal matrices (:data:`scipy.stats.ortho_group`) and x* a random shift, uniform in
[−4, 4]^d as in BBOB, all drawn from a seed fixed per function and dimension (the CRC-32 of its name), so every run
sees the same valley.  Every function is 0 at x* and only there (``f_min`` = 0, ``x_min`` = x*).  Two departures
from BBOB: no additive f_opt (the minimum is 0), and the ellipsoid has no oscillation T_osz (a small
non-smooth ripple that is not what these functions are here to measure).  T_asy^β(x)_i = x_i^(1 + β (i−1)/(d−1)
√x_i) where x_i > 0, x_i otherwise; Λ^α = diag(α^((i−1)/(2 (d−1)))).

``f_range`` is max − min over the box from :func:`~mechopt.studies.benchmark_functions.sampled_range` with 2^16
Sobol points (the corners and the ascents decide it), to 5 significant digits.
"""

from __future__ import annotations

import zlib
from typing import ClassVar

import numpy as np
from scipy.stats import ortho_group

from mechopt.optimize.problem import Variable
from mechopt.studies.benchmark_functions import SUITE, TestFunction

__all__ = ["VALLEYS", "BentCigar", "DifferentPowers", "Ellipsoid", "RotatedRosenbrock", "SharpRidge", "Valley"]

#: Half-width of the box [−5, 5]^d and of the cube [−4, 4]^d the shift is drawn from (BBOB's).
BOX_HALF_WIDTH = 5.0
SHIFT_HALF_WIDTH = 4.0


class Valley(TestFunction):
    """A BBOB function of z, the rotated and shifted design: a subclass sets ``dimension`` and gets its variables,
    rotations and shift, drawn once from the seed of its name.

    Attributes
    ----------
    dimension : int
        Number of variables d.
    rotation, second_rotation : (d, d) ndarray
        R and Q, orthogonal.
    shift : (d,) ndarray
        x*, the minimiser.
    """

    dimension: ClassVar[int] = 0
    rotation: ClassVar[np.ndarray]
    second_rotation: ClassVar[np.ndarray]
    shift: ClassVar[np.ndarray]
    f_min = 0.0
    f_second = np.nan
    range_grid = 0

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        d = cls.__dict__.get("dimension", 0)
        if not d:
            return
        rng = np.random.default_rng(zlib.crc32(cls.name.encode()))
        cls.rotation = ortho_group.rvs(d, random_state=rng)
        cls.second_rotation = ortho_group.rvs(d, random_state=rng)
        cls.shift = rng.uniform(-SHIFT_HALF_WIDTH, SHIFT_HALF_WIDTH, d)
        cls.x_min = cls.shift[None, :].copy()
        cls.variables = tuple(Variable(f"x{i + 1}", -BOX_HALF_WIDTH, BOX_HALF_WIDTH) for i in range(d))

    @staticmethod
    def ramp(d: int) -> np.ndarray:
        """(i − 1)/(d − 1) for i = 1..d: the exponent ramp of BBOB's conditioning, shape (d,)."""
        return np.arange(d) / (d - 1)

    def rotated(self, X: np.ndarray) -> np.ndarray:
        """R (x − x*) for each row of X (n, d), shape (n, d)."""
        return (X - self.shift) @ self.rotation.T

    def function(self, X: np.ndarray) -> np.ndarray:
        return self.core(self.rotated(X))

    def core(self, Z: np.ndarray) -> np.ndarray:
        """The function of the rotated, shifted designs Z (n, d), shape (n,)."""
        raise NotImplementedError


class Ellipsoid(Valley):
    """BBOB f10, the rotated ellipsoid Σ 10^(6 (i−1)/(d−1)) z_i²: condition 10^6, 0 at a shifted x*."""

    def core(self, Z: np.ndarray) -> np.ndarray:
        return (Z * Z) @ (10.0 ** (6.0 * self.ramp(Z.shape[1])))


class BentCigar(Valley):
    """BBOB f12, the bent cigar z_1² + 10^6 Σ_{i>=2} z_i², z = R T_asy^0.5(R (x − x*)): a thin curved valley."""

    def core(self, Z: np.ndarray) -> np.ndarray:
        exponent = 1.0 + 0.5 * self.ramp(Z.shape[1]) * np.sqrt(np.maximum(Z, 0.0))
        bent = np.where(Z > 0.0, np.abs(Z) ** exponent, Z)
        W = bent @ self.rotation.T
        return W[:, 0] ** 2 + 1e6 * np.sum(W[:, 1:] ** 2, axis=1)


class RotatedRosenbrock(Valley):
    """BBOB f9, Rosenbrock Σ 100 (z_i² − z_{i+1})² + (z_i − 1)², z = max(1, √d/8) R (x − x*) + 1: a bent valley."""

    def core(self, Z: np.ndarray) -> np.ndarray:
        Z = max(1.0, np.sqrt(Z.shape[1]) / 8.0) * Z + 1.0
        return np.sum(100.0 * (Z[:, :-1] ** 2 - Z[:, 1:]) ** 2 + (Z[:, :-1] - 1.0) ** 2, axis=1)


class SharpRidge(Valley):
    """BBOB f13, the sharp ridge z_1² + 100 √(Σ_{i>=2} z_i²), z = Q Λ^10 R (x − x*): a ridge with a kink."""

    def core(self, Z: np.ndarray) -> np.ndarray:
        W = (Z * 10.0 ** (0.5 * self.ramp(Z.shape[1]))) @ self.second_rotation.T
        return W[:, 0] ** 2 + 100.0 * np.sqrt(np.sum(W[:, 1:] ** 2, axis=1))


class DifferentPowers(Valley):
    """BBOB f14, the sum of different powers √(Σ |z_i|^(2 + 4 (i−1)/(d−1))): flat along some axes, steep along
    others."""

    def core(self, Z: np.ndarray) -> np.ndarray:
        return np.sqrt(np.sum(np.abs(Z) ** (2.0 + 4.0 * self.ramp(Z.shape[1])), axis=1))


class Ellipsoid3(Ellipsoid):
    """Rotated ellipsoid of condition 10^6 (BBOB f10) on [−5, 5]^3, shifted: 0 at x*."""

    name, dimension, f_range = "valley_ellipsoid3", 3, 8.2404e7


class Ellipsoid6(Ellipsoid):
    """Rotated ellipsoid of condition 10^6 (BBOB f10) on [−5, 5]^6, shifted: 0 at x*."""

    name, dimension, f_range = "valley_ellipsoid6", 6, 1.1028e8


class Ellipsoid10(Ellipsoid):
    """Rotated ellipsoid of condition 10^6 (BBOB f10) on [−5, 5]^10, shifted: 0 at x*."""

    name, dimension, f_range = "valley_ellipsoid10", 10, 2.0971e8


class BentCigar3(BentCigar):
    """Rotated bent cigar (BBOB f12) on [−5, 5]^3, shifted: 0 at x*."""

    name, dimension, f_range = "valley_bent_cigar3", 3, 2.0382e11


class BentCigar6(BentCigar):
    """Rotated bent cigar (BBOB f12) on [−5, 5]^6, shifted: 0 at x*."""

    name, dimension, f_range = "valley_bent_cigar6", 6, 7.1247e11


class BentCigar10(BentCigar):
    """Rotated bent cigar (BBOB f12) on [−5, 5]^10, shifted: 0 at x*."""

    name, dimension, f_range = "valley_bent_cigar10", 10, 5.4212e11


class RotatedRosenbrock3(RotatedRosenbrock):
    """Rotated Rosenbrock (BBOB f9) on [−5, 5]^3, shifted: 0 at x*."""

    name, dimension, f_range = "valley_rosenbrock3", 3, 8.4230e5


class RotatedRosenbrock6(RotatedRosenbrock):
    """Rotated Rosenbrock (BBOB f9) on [−5, 5]^6, shifted: 0 at x*."""

    name, dimension, f_range = "valley_rosenbrock6", 6, 3.3104e6


class RotatedRosenbrock10(RotatedRosenbrock):
    """Rotated Rosenbrock (BBOB f9) on [−5, 5]^10, shifted: 0 at x*."""

    name, dimension, f_range = "valley_rosenbrock10", 10, 1.7281e7


class SharpRidge3(SharpRidge):
    """Rotated sharp ridge (BBOB f13) on [−5, 5]^3, shifted: 0 at x*."""

    name, dimension, f_range = "valley_sharp_ridge3", 3, 2729.8


class SharpRidge6(SharpRidge):
    """Rotated sharp ridge (BBOB f13) on [−5, 5]^6, shifted: 0 at x*."""

    name, dimension, f_range = "valley_sharp_ridge6", 6, 3861.2


class SharpRidge10(SharpRidge):
    """Rotated sharp ridge (BBOB f13) on [−5, 5]^10, shifted: 0 at x*."""

    name, dimension, f_range = "valley_sharp_ridge10", 10, 5929.5


class DifferentPowers3(DifferentPowers):
    """Rotated sum of different powers (BBOB f14) on [−5, 5]^3, shifted: 0 at x*."""

    name, dimension, f_range = "valley_different_powers3", 3, 534.21


class DifferentPowers6(DifferentPowers):
    """Rotated sum of different powers (BBOB f14) on [−5, 5]^6, shifted: 0 at x*."""

    name, dimension, f_range = "valley_different_powers6", 6, 2768.8


class DifferentPowers10(DifferentPowers):
    """Rotated sum of different powers (BBOB f14) on [−5, 5]^10, shifted: 0 at x*."""

    name, dimension, f_range = "valley_different_powers10", 10, 2111.5


VALLEY_CLASSES: tuple[type[Valley], ...] = (
    Ellipsoid3,
    Ellipsoid6,
    Ellipsoid10,
    BentCigar3,
    BentCigar6,
    BentCigar10,
    RotatedRosenbrock3,
    RotatedRosenbrock6,
    RotatedRosenbrock10,
    SharpRidge3,
    SharpRidge6,
    SharpRidge10,
    DifferentPowers3,
    DifferentPowers6,
    DifferentPowers10,
)

#: The valleys, by name.
VALLEYS: dict[str, type[Valley]] = {cls.name: cls for cls in VALLEY_CLASSES}

# The suite of `compare` and of the default method's benchmark holds the valleys beside the multimodal functions.
SUITE.update(VALLEYS)
