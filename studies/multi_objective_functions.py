"""Test problems with several objectives, some with limits: the suite on which the default method's fronts are measured.

Each problem is a :class:`~mechopt.optimize.problem.DesignProblem` whose outputs are its objectives ``f1..fk`` and,
for the constrained ones, its constraints ``c1..cm`` written as pymoo writes them (feasible where c <= 0), each a
limit ``(None, 0)`` on a simulated output: the method must learn them from simulations.  The definitions are pymoo's
(``pymoo.problems.multi``; ``tests/studies/test_multi_objective_functions.py`` checks the values against pymoo's own
implementations): ZDT1-3 (Zitzler, Deb & Thiele 2000), DTLZ2 (Deb, Thiele, Laumanns & Zitzler 2002), BNH (Binh &
Korn 1997), SRN (Srinivas & Deb 1994), TNK (Tanaka 1995) and OSY (Osyczka & Kundu 1995).

``ideal`` and ``nadir`` are the least and the largest value of each objective over the true Pareto front (pymoo's
``pareto_front()`` where it ships one offline; the literature's values for TNK and OSY): the benchmark's
hypervolume normalises each objective to z = (f − ideal) / (nadir − ideal) with reference point z = 1.1
(:mod:`mechopt.optimize.pareto`).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from mechopt.optimize.problem import DesignProblem, Variable

__all__ = ["BNH", "DTLZ2", "DTLZ2_3", "MULTI_OBJECTIVE_SUITE", "OSY", "SRN", "TNK", "ZDT1", "ZDT2", "ZDT3",
           "FrontProblem"]


class FrontProblem(DesignProblem):
    """A problem of several objectives with a vectorised closed form and a known front.

    Attributes
    ----------
    ideal, nadir : (k,) ndarray
        Least and largest value of each objective over the true front.
    n_constraints : int
        Constraint outputs ``c1..cm``, each limited to <= 0.
    """

    __test__ = False
    fit = "value"
    n_objectives: ClassVar[int] = 2
    n_constraints: ClassVar[int] = 0
    ideal: ClassVar[np.ndarray] = np.zeros(2)
    nadir: ClassVar[np.ndarray] = np.ones(2)

    def __init__(self) -> None:
        f = tuple(f"f{i + 1}" for i in range(self.n_objectives))
        c = tuple(f"c{i + 1}" for i in range(self.n_constraints))
        self.outputs = f + c
        self.objective = f
        self.limits = {name: (None, 0.0) for name in c}

    @classmethod
    def summary(cls) -> str:
        """The docstring's first paragraph on one line: the catalogue's description."""
        paragraph = (cls.__doc__ or cls.__name__).strip().split("\n\n")[0]
        return " ".join(paragraph.split()).replace("``", "").rstrip(".")

    def function(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Objectives (n, k) and constraints (n, m) of designs X (n, d)."""
        raise NotImplementedError

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        """Outputs ``f1..fk, c1..cm`` of one design."""
        F, G = self.function(np.asarray(x, dtype=float)[None, :])
        return {name: float(v) for name, v in zip(self.outputs, np.concatenate([F[0], G[0]]), strict=True)}


def _unit_box(d: int) -> tuple[Variable, ...]:
    return tuple(Variable(f"x{i + 1}", 0.0, 1.0) for i in range(d))


def _none(X: np.ndarray) -> np.ndarray:
    return np.zeros((X.shape[0], 0))


class _ZDT(FrontProblem):
    variables = _unit_box(5)

    def _g(self, X: np.ndarray) -> np.ndarray:
        return 1.0 + 9.0 * X[:, 1:].sum(axis=1) / (X.shape[1] - 1)


class ZDT1(_ZDT):
    """ZDT1 in 5 variables: a convex front f2 = 1 − sqrt(f1)."""

    name = "zdt1"

    def function(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        g = self._g(X)
        return np.column_stack([X[:, 0], g * (1.0 - np.sqrt(X[:, 0] / g))]), _none(X)


class ZDT2(_ZDT):
    """ZDT2 in 5 variables: a concave front f2 = 1 − f1²."""

    name = "zdt2"

    def function(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        g = self._g(X)
        return np.column_stack([X[:, 0], g * (1.0 - (X[:, 0] / g) ** 2)]), _none(X)


class ZDT3(_ZDT):
    """ZDT3 in 5 variables: a front in five disconnected pieces."""

    name = "zdt3"
    ideal: ClassVar[np.ndarray] = np.array([0.0, -0.77336901])
    nadir: ClassVar[np.ndarray] = np.array([0.85183287, 1.0])

    def function(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        g, f1 = self._g(X), X[:, 0]
        f2 = g * (1.0 - np.sqrt(f1 / g) - f1 / g * np.sin(10.0 * np.pi * f1))
        return np.column_stack([f1, f2]), _none(X)


def _dtlz2(X: np.ndarray, k: int) -> np.ndarray:
    """DTLZ2 with k objectives: the unit sphere's positive orthant scaled by 1 + g."""
    g = np.sum((X[:, k - 1:] - 0.5) ** 2, axis=1)
    angles = X[:, : k - 1] * np.pi / 2.0
    F = np.tile((1.0 + g)[:, None], (1, k))
    for j in range(k):
        F[:, j] *= np.prod(np.cos(angles[:, : k - 1 - j]), axis=1)
        if j > 0:
            F[:, j] *= np.sin(angles[:, k - 1 - j])
    return F


class DTLZ2(FrontProblem):
    """DTLZ2 in 5 variables, two objectives: a quarter circle f1² + f2² = 1."""

    name = "dtlz2"
    variables = _unit_box(5)

    def function(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return _dtlz2(X, 2), _none(X)


class DTLZ2_3(FrontProblem):  # noqa: N801 - the literature's name and its number of objectives
    """DTLZ2 in 6 variables, three objectives: an eighth of the unit sphere."""

    name = "dtlz2-3"
    variables = _unit_box(6)
    n_objectives = 3
    ideal: ClassVar[np.ndarray] = np.zeros(3)
    nadir: ClassVar[np.ndarray] = np.ones(3)

    def function(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return _dtlz2(X, 3), _none(X)


class BNH(FrontProblem):
    """BNH (Binh and Korn): two variables, two quadratic objectives, two limits."""

    name = "bnh"
    variables = (Variable("x1", 0.0, 5.0), Variable("x2", 0.0, 3.0))
    n_constraints = 2
    ideal: ClassVar[np.ndarray] = np.array([0.0, 4.0])
    nadir: ClassVar[np.ndarray] = np.array([136.0, 50.0])

    def function(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x1, x2 = X[:, 0], X[:, 1]
        F = np.column_stack([4.0 * x1**2 + 4.0 * x2**2, (x1 - 5.0) ** 2 + (x2 - 5.0) ** 2])
        G = np.column_stack([((x1 - 5.0) ** 2 + x2**2 - 25.0) / 25.0, -((x1 - 8.0) ** 2 + (x2 + 3.0) ** 2 - 7.7) / 7.7])
        return F, G


class SRN(FrontProblem):
    """SRN (Srinivas and Deb): two variables in [-20, 20], two objectives, two limits."""

    name = "srn"
    variables = (Variable("x1", -20.0, 20.0), Variable("x2", -20.0, 20.0))
    n_constraints = 2
    ideal: ClassVar[np.ndarray] = np.array([24.5, -212.66961604])
    nadir: ClassVar[np.ndarray] = np.array([212.41961604, -24.75])

    def function(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x1, x2 = X[:, 0], X[:, 1]
        F = np.column_stack([2.0 + (x1 - 2.0) ** 2 + (x2 - 1.0) ** 2, 9.0 * x1 - (x2 - 1.0) ** 2])
        G = np.column_stack([x1**2 + x2**2 - 225.0, x1 - 3.0 * x2 + 10.0])
        return F, G


class TNK(FrontProblem):
    """TNK (Tanaka): two variables, the objectives are the variables, a wavy limit makes the front disconnected."""

    name = "tnk"
    variables = (Variable("x1", 0.0, np.pi), Variable("x2", 1e-30, np.pi))
    n_constraints = 2
    ideal: ClassVar[np.ndarray] = np.array([0.0417, 0.0417])
    nadir: ClassVar[np.ndarray] = np.array([1.0387, 1.0387])

    def function(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x1, x2 = X[:, 0], X[:, 1]
        g1 = -(x1**2 + x2**2 - 1.0 - 0.1 * np.cos(16.0 * np.arctan(x1 / x2)))
        g2 = 2.0 * ((x1 - 0.5) ** 2 + (x2 - 0.5) ** 2) - 1.0
        return np.column_stack([x1, x2]), np.column_stack([g1, g2])


class OSY(FrontProblem):
    """OSY (Osyczka and Kundu): six variables, two objectives, six limits."""

    name = "osy"
    variables = (Variable("x1", 0.0, 10.0), Variable("x2", 0.0, 10.0), Variable("x3", 1.0, 5.0),
                 Variable("x4", 0.0, 6.0), Variable("x5", 1.0, 5.0), Variable("x6", 0.0, 10.0))
    n_constraints = 6
    ideal: ClassVar[np.ndarray] = np.array([-274.0, 4.0])
    nadir: ClassVar[np.ndarray] = np.array([-42.0, 76.0])

    def function(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x = [X[:, i] for i in range(6)]
        f1 = -(25.0 * (x[0] - 2.0) ** 2 + (x[1] - 2.0) ** 2 + (x[2] - 1.0) ** 2 + (x[3] - 4.0) ** 2
               + (x[4] - 1.0) ** 2)
        f2 = np.sum(X**2, axis=1)
        G = -np.column_stack([(x[0] + x[1] - 2.0) / 2.0, (6.0 - x[0] - x[1]) / 6.0, (2.0 - x[1] + x[0]) / 2.0,
                              (2.0 - x[0] + 3.0 * x[1]) / 2.0, (4.0 - (x[2] - 3.0) ** 2 - x[3]) / 4.0,
                              ((x[4] - 3.0) ** 2 + x[5] - 4.0) / 4.0])
        return np.column_stack([f1, f2]), G


#: Every problem of the suite by name.
MULTI_OBJECTIVE_SUITE: dict[str, type[FrontProblem]] = {
    cls.name: cls for cls in (ZDT1, ZDT2, ZDT3, DTLZ2, DTLZ2_3, BNH, SRN, TNK, OSY)
}
