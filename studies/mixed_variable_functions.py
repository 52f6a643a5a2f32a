"""Mixed-variable engineering problems of the literature: the suite on which discrete variables are measured.

Each problem is a :class:`~mechopt.studies.benchmark_functions.TestFunction` whose variables mix continuous ones with
a drawing grid (``step``), integers and a catalogue (``values``), its constraints written as margins (>= 0 feasible,
each scaled to a dimensionless ratio so that no constraint dwarfs another), and its best known design ``x_min`` with
value ``f_min`` from the literature, cited in its docstring.  ``tests/studies/test_mixed_variable_functions.py``
reproduces each value at its design and checks that the design is feasible and allowed.

The printed designs of these problems are rounded: a design printed to 6 digits may violate an active constraint by
1e-6 and change the value in its fifth digit.  ``x_min`` is therefore the design on the active constraints solved to
full precision (then moved by less than 1e-9 into the feasible side), and each docstring says how its value compares
with the printed one.  The gap of a comparison is ``100 (f / f_min - 1)`` per cent (no range over the box is
declared: these problems span orders of magnitude over their boxes).
"""

from __future__ import annotations

import numpy as np

from mechopt.optimize.variable import Variable
from mechopt.studies.benchmark_functions import TestFunction

__all__ = ["MIXED_SUITE", "CoilSpring", "GearTrain", "MixedProblem", "PressureVessel", "SpeedReducer",
           "WIRE_DIAMETERS_IN"]


class MixedProblem(TestFunction):
    """A test function with discrete variables and a best known design from the literature.

    Attributes
    ----------
    f_min : float
        Best known value (the literature's, recomputed at ``x_min``).
    x_min : (1, d) ndarray
        Best known design, allowed and feasible.
    """

    __test__ = False

    def in_global_basin(self, x: np.ndarray, tol: float = 1e-2) -> bool:
        """Whether ``x`` is the best known design to ``tol`` of each variable's range (no descent: the variables
        are discrete)."""
        b = self.bounds
        return bool(np.all(np.abs(np.asarray(x, float) - self.x_min[0]) <= tol * (b[:, 1] - b[:, 0])))


class PressureVessel(MixedProblem):
    """Sandgren's pressure vessel: cost of a cylindrical vessel with hemispherical heads, shell and head plates in
    multiples of 1/16 in, radius and length continuous; 4 limits, best known 6059.7143.

    Minimise ``0.6224 Ts R L + 1.7781 Th R² + 3.1661 Ts² L + 19.84 Ts² R`` (material, forming and welding cost) over
    the shell thickness ``ts`` and head thickness ``th`` (in, 1..99 times 0.0625: Kannan & Kramer's bounds), the
    inner radius ``r`` and the length ``l`` of the cylinder (in, [10, 200]) subject to ASME thickness rules
    ``Ts >= 0.0193 R`` and ``Th >= 0.00954 R``, a volume of at least 1 296 000 in³ (750 ft³) and ``L <= 240`` in.

    Sandgren, E. (1990) Nonlinear integer and discrete programming in mechanical design optimization, J. Mech. Des.
    112(2) 223-229; Kannan, B.K. & Kramer, S.N. (1994) J. Mech. Des. 116(2) 405-411 (the bounds).  Best known
    f = 6059.7143 at (0.8125, 0.4375, 42.0984456, 176.6365958) (e.g. Coello & Mezura-Montes 2002): both thickness
    and volume limits active; at the printed radius and length the shell-thickness limit is violated by 8e-11 in.
    ``x_min`` solves the two active limits exactly: f = 6059.714335.
    """

    name = "pressure_vessel"
    variables = (Variable("ts", 0.0625, 6.1875, "in", "Ts", step=0.0625),
                 Variable("th", 0.0625, 6.1875, "in", "Th", step=0.0625),
                 Variable("r", 10.0, 200.0, "in", "R"), Variable("l", 10.0, 200.0, "in", "L"))
    constraints = ("shell_thickness", "head_thickness", "volume", "length")
    f_min = 6059.714335048436
    x_min = np.array([[0.8125, 0.4375, 42.098445595, 176.636595860]])

    def margins(self, X: np.ndarray) -> np.ndarray:
        ts, th, r, length = X.T
        volume = np.pi * r**2 * length + 4.0 / 3.0 * np.pi * r**3
        return np.column_stack([ts / (0.0193 * r) - 1.0, th / (0.00954 * r) - 1.0, volume / 1.296e6 - 1.0,
                                1.0 - length / 240.0])

    def function(self, X: np.ndarray) -> np.ndarray:
        ts, th, r, length = X.T
        return 0.6224 * ts * r * length + 1.7781 * th * r**2 + 3.1661 * ts**2 * length + 19.84 * ts**2 * r


class GearTrain(MixedProblem):
    """Sandgren's gear train: four integer tooth counts 12..60 whose ratio Td Tb / (Ta Tf) is nearest 1/6.931; best
    known 2.700857e-12.

    Minimise ``(1/6.931 − Td Tb / (Ta Tf))²`` without limits; 49⁴ = 5 764 801 designs.  Sandgren (1990), above;
    best known 2.700857e-12 at (Td, Tb, Ta, Tf) = (16, 19, 43, 49) (Deb & Goyal 1996; also (19, 16, 43, 49) and
    the swaps of Ta and Tf), reproduced to its printed digits: 2.7008571e-12.
    """

    name = "gear_train"
    variables = tuple(Variable(n, 12.0, 60.0, "", n.capitalize(), integer=True) for n in ("td", "tb", "ta", "tf"))
    f_min = 2.7008571488865134e-12
    x_min = np.array([[16.0, 19.0, 43.0, 49.0]])

    def function(self, X: np.ndarray) -> np.ndarray:
        td, tb, ta, tf = X.T
        return (1.0 / 6.931 - td * tb / (ta * tf)) ** 2


#: The 42 standard wire diameters of the coil spring (in), Sandgren (1990), as tabled by Lampinen & Zelinka (1999).
WIRE_DIAMETERS_IN = (0.009, 0.0095, 0.0104, 0.0118, 0.0128, 0.0132, 0.014, 0.015, 0.0162, 0.0173, 0.018, 0.020,
                     0.023, 0.025, 0.028, 0.032, 0.035, 0.041, 0.047, 0.054, 0.063, 0.072, 0.080, 0.092, 0.105, 0.120,
                     0.135, 0.148, 0.162, 0.177, 0.192, 0.207, 0.225, 0.244, 0.263, 0.283, 0.307, 0.331, 0.362, 0.394,
                     0.4375, 0.500)


class CoilSpring(MixedProblem):
    """Sandgren's coil compression spring: volume of wire, an integer number of coils, the wire from a catalogue of
    42 standard diameters, the coil diameter continuous; 7 limits, best known 2.65856.

    Minimise ``π² D d² (N + 2) / 4`` (in³) over the active coils ``n`` (1..70), the wire diameter ``d`` (in, the
    catalogue :data:`WIRE_DIAMETERS_IN`) and the coil diameter ``coil`` (D, in, [0.6, 3]) for a spring of maximum
    load 1000 lb and preload 300 lb (G = 11.5e6 psi): shear stress ``8 Cf Fmax D / (π d³) <= 189 000`` psi with
    Wahl's factor ``Cf = (4C − 1)/(4C − 4) + 0.615/C``, ``C = D/d``; free length ``Fmax/K + 1.05 (N + 2) d <= 14`` in
    with ``K = G d⁴ / (8 N D³)``; ``d >= 0.2`` in; outer diameter ``D + d <= 3`` in; ``C >= 3``; preload deflection
    ``Fp/K <= 6`` in; working deflection ``(Fmax − Fp)/K >= 1.25`` in.  Sandgren's seventh limit (free length from
    the deflections) is identically zero (``Fp/K + (Fmax − Fp)/K = Fmax/K``) and is left out.

    Sandgren (1990), above; Kannan & Kramer (1994), above (2.7995 at N = 10); Lampinen, J. & Zelinka, I. (1999)
    Mixed integer-discrete-continuous optimization by differential evolution, Proc. MENDEL'99 71-76: best known
    2.65856 at (N, D, d) = (9, 1.223041, 0.283), where the working-deflection limit is active and violated by 3e-8
    in at the printed D.  ``x_min`` solves it exactly: D = 1.2230410100, f = 2.6585592.
    """

    name = "coil_spring"
    variables = (Variable("n", 1.0, 70.0, "", "N", integer=True),
                 Variable("coil", 0.6, 3.0, "in", "D"),
                 Variable("d", unit="in", label="d", values=WIRE_DIAMETERS_IN))
    constraints = ("shear_stress", "free_length", "wire_min", "outer_diameter", "spring_index", "preload_deflection",
                   "working_deflection")
    f_min = 2.6585591659695993
    x_min = np.array([[9.0, 1.223041010, 0.283]])

    def margins(self, X: np.ndarray) -> np.ndarray:
        n, coil, d = X.T
        c = coil / d
        wahl = (4.0 * c - 1.0) / (4.0 * c - 4.0) + 0.615 / c
        stiffness = 11.5e6 * d**4 / (8.0 * n * coil**3)
        shear = 8.0 * wahl * 1000.0 * coil / (np.pi * d**3)
        free_length = 1000.0 / stiffness + 1.05 * (n + 2.0) * d
        return np.column_stack([1.0 - shear / 189e3, 1.0 - free_length / 14.0, d / 0.2 - 1.0, 1.0 - (coil + d) / 3.0,
                                c / 3.0 - 1.0, 1.0 - 300.0 / stiffness / 6.0, 700.0 / stiffness / 1.25 - 1.0])

    def function(self, X: np.ndarray) -> np.ndarray:
        n, coil, d = X.T
        return np.pi**2 * coil * d**2 * (n + 2.0) / 4.0


class SpeedReducer(MixedProblem):
    """Golinski's speed reducer: weight of a two-shaft gearbox, the number of pinion teeth an integer 17..28, six
    dimensions continuous; 11 limits, best known 2994.4711.

    Minimise ``0.7854 b m² (3.3333 z² + 14.9334 z − 43.0934) − 1.508 b (d1² + d2²) + 7.4777 (d1³ + d2³) + 0.7854
    (l1 d1² + l2 d2²)`` over the face width ``b`` [2.6, 3.6], the module ``m`` [0.7, 0.8], the teeth ``z``, the shaft
    lengths between bearings ``l1``, ``l2`` [7.3, 8.3] and the shaft diameters ``d1`` [2.9, 3.9], ``d2`` [5.0, 5.5]
    (Golinski's units: cm), subject to bending and contact stress of the teeth, deflections and stresses of the
    shafts and dimensional rules (11 limits, each written ``1 − g >= 0`` from the literature's ``g <= 1``).

    Golinski, J. (1970) Optimal synthesis problems solved by means of nonlinear programming and random methods,
    J. Mechanisms 5, 287-309; in this form Ray, T. & Saini, P. (2001) Eng. Optim. 33(6) 735-748.  Best known
    2994.4710661 at (3.5, 0.7, 17, 7.3, 7.71532, 3.35021, 5.28665) (Mezura-Montes & Coello 2005); at the printed
    design the two shaft-stress limits are violated by 4e-6 and 3e-6 and f = 2994.4670.  ``x_min`` solves the five
    active limits exactly: f = 2994.4710661.
    """

    name = "speed_reducer"
    variables = (Variable("b", 2.6, 3.6, "cm", "b"), Variable("m", 0.7, 0.8, "cm", "m"),
                 Variable("z", 17.0, 28.0, "", "z", integer=True), Variable("l1", 7.3, 8.3, "cm", "l1"),
                 Variable("l2", 7.3, 8.3, "cm", "l2"), Variable("d1", 2.9, 3.9, "cm", "d1"),
                 Variable("d2", 5.0, 5.5, "cm", "d2"))
    constraints = ("bending", "contact", "deflection_1", "deflection_2", "shaft_stress_1", "shaft_stress_2",
                   "width_teeth", "width_ratio_min", "width_ratio_max", "shaft_1", "shaft_2")
    f_min = 2994.4710661468202
    x_min = np.array([[3.5, 0.7, 17.0, 7.3, 7.715319912, 3.350214667, 5.286654465]])

    def margins(self, X: np.ndarray) -> np.ndarray:
        b, m, z, l1, l2, d1, d2 = X.T
        g = [27.0 / (b * m**2 * z), 397.5 / (b * m**2 * z**2), 1.93 * l1**3 / (m * z * d1**4),
             1.93 * l2**3 / (m * z * d2**4), np.sqrt((745.0 * l1 / (m * z)) ** 2 + 16.9e6) / (110.0 * d1**3),
             np.sqrt((745.0 * l2 / (m * z)) ** 2 + 157.5e6) / (85.0 * d2**3), m * z / 40.0, 5.0 * m / b,
             b / (12.0 * m), (1.5 * d1 + 1.9) / l1, (1.1 * d2 + 1.9) / l2]
        return 1.0 - np.column_stack(g)

    def function(self, X: np.ndarray) -> np.ndarray:
        b, m, z, l1, l2, d1, d2 = X.T
        return (0.7854 * b * m**2 * (3.3333 * z**2 + 14.9334 * z - 43.0934) - 1.508 * b * (d1**2 + d2**2)
                + 7.4777 * (d1**3 + d2**3) + 0.7854 * (l1 * d1**2 + l2 * d2**2))


#: Every problem of the suite by name.
MIXED_SUITE: dict[str, type[MixedProblem]] = {
    cls.name: cls for cls in (PressureVessel, GearTrain, CoilSpring, SpeedReducer)
}
