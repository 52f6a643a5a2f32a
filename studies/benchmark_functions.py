"""Multimodal test functions as design problems: the suite on which the global strategy is measured.

Each problem is a :class:`~mechopt.optimize.problem.DesignProblem` with its known global minimum ``f_min``, every
global minimiser ``x_min`` (one row per minimiser: Branin and the six-hump camel have several), the value of the
second-best local minimum ``f_second`` and the range of the function over the (feasible) box, ``f_range`` = max − min,
measured once on a dense grid (:func:`dense_grid_range` with the grid recorded in ``range_grid``; the printed
constants below are max − ``f_min`` from that function's output, to 5 significant digits).

:meth:`TestFunction.in_global_basin` decides whether a design lies in the basin of a global minimiser: a local
descent on the function itself (L-BFGS-B in the box, SLSQP when there are constraints) started there must end at one
of the ``x_min``.  ``gap`` is (f(x) − f_min) / f_range, the measure of the benchmarks.

References: Dixon & Szegő (1978) for Hartmann-3, Branin and the six-hump camel; Himmelblau (1972); the cosine
function is mechopt's own (a quadratic bowl with a product of cosines, 31 local minima in [0, 1]^3).
"""

from __future__ import annotations

import hashlib
from typing import ClassVar

import numpy as np
from scipy.optimize import minimize

from mechopt.optimize.problem import DesignProblem, Variable

__all__ = [
    "SUITE",
    "Branin",
    "Ackley8",
    "CosineBowl3",
    "CosineBowl4",
    "FailingHartmann3",
    "Hartmann3",
    "Hartmann4",
    "Hartmann6",
    "Levy8",
    "NoisyHartmann6",
    "Rosenbrock6",
    "StyblinskiTang3",
    "HimmelblauDisc",
    "SixHumpCamel",
    "TestFunction",
    "dense_grid_range",
    "sampled_range",
]


class TestFunction(DesignProblem):
    """A design problem with a vectorised closed form and known minima.

    Attributes
    ----------
    f_min : float
        Global minimum over the feasible box.
    x_min : (k, d) ndarray
        Every global minimiser.
    f_second : float
        Value of the best local minimum that is not global (for reports).
    f_range : float
        max − min of the function over the feasible box (dense grid, see :func:`dense_grid_range`).
    range_grid : int
        Points per axis of the grid that measured ``f_range``.
    """

    __test__ = False  # not a pytest class despite the name
    outputs = ("f",)
    objective = "f"
    fit = "value"
    f_min: ClassVar[float] = np.nan
    x_min: ClassVar[np.ndarray] = np.zeros((0, 0))
    f_second: ClassVar[float] = np.nan
    f_range: ClassVar[float] = np.nan
    range_grid: ClassVar[int] = 0

    @classmethod
    def summary(cls) -> str:
        """The docstring's first paragraph on one line, without reST markup: the catalogue's description."""
        paragraph = (cls.__doc__ or cls.__name__).strip().split("\n\n")[0]
        return " ".join(paragraph.split()).replace("``", "").rstrip(".")

    def function(self, X: np.ndarray) -> np.ndarray:
        """The function at designs X (n, d), shape (n,)."""
        raise NotImplementedError

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """Batch evaluator: f at designs (n, d), shape (n,)."""
        return self.function(np.atleast_2d(np.asarray(X, dtype=float)))

    def evaluate_batch(self, X: np.ndarray) -> np.ndarray:
        """The closed form at designs (n, d): the fast evaluator a comparison scores returned designs with (for a
        noisy function, its value without the noise)."""
        return self(X)

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        """The function at one design (d,), as ``{"f": value}``."""
        return {"f": float(self(np.asarray(x, dtype=float)[None, :])[0])}

    def sampleable(self, X: np.ndarray) -> np.ndarray:
        """The closed form is defined on the whole box: lines may cross a constraint but not a bound."""
        return self.in_box(X)

    def gap(self, fun: float) -> float:
        """(fun − f_min) / f_range, the fraction of the function's range by which ``fun`` misses the minimum."""
        return (float(fun) - self.f_min) / self.f_range

    def in_global_basin(self, x: np.ndarray, tol: float = 1e-2) -> bool:
        """Whether a local descent on the function from ``x`` ends at a global minimiser.

        Parameters
        ----------
        x : (d,) ndarray
            Design.
        tol : float
            Largest distance of the descent's end from a minimiser, as a fraction of the box's largest width.
        """
        b = self.bounds
        x = np.clip(np.asarray(x, dtype=float), b[:, 0], b[:, 1])
        width = b[:, 1] - b[:, 0]

        def fun(u: np.ndarray) -> float:
            return float(self(b[:, 0] + u * width)[0])

        u0 = (x - b[:, 0]) / width
        if self.constraints:
            cons = [{"type": "ineq", "fun": lambda u: self.margins((b[:, 0] + u * width)[None, :])[0]}]
            res = minimize(fun, u0, method="SLSQP", bounds=[(0, 1)] * self.dim, constraints=cons,
                           options={"ftol": 1e-12, "maxiter": 500})
        else:
            res = minimize(fun, u0, method="L-BFGS-B", bounds=[(0, 1)] * self.dim,
                           options={"ftol": 1e-14, "gtol": 1e-10})
        end = b[:, 0] + res.x * width
        return bool(np.min(np.linalg.norm(self.x_min - end, axis=1)) <= tol * width.max())


def dense_grid_range(problem: TestFunction, n: int) -> tuple[float, float]:
    """Smallest and largest value of the function on the feasible points of an n^d tensor grid of the box.

    Parameters
    ----------
    problem : TestFunction
    n : int
        Points per axis (both bounds included).

    Returns
    -------
    (float, float)
        min and max over the feasible grid points.
    """
    axes = [np.linspace(v.lower, v.upper, n) for v in problem.variables]
    lo, hi = np.inf, -np.inf
    # Chunk over the first axis so a 400^3 grid does not need 64 million rows at once.
    for a in axes[0]:
        rest = np.stack(np.meshgrid(*axes[1:], indexing="ij"), axis=-1).reshape(-1, problem.dim - 1)
        X = np.column_stack([np.full(rest.shape[0], a), rest])
        X = X[problem.feasible(X)]
        if X.shape[0]:
            f = problem(X)
            lo, hi = min(lo, float(f.min())), max(hi, float(f.max()))
    return lo, hi


class Hartmann3(TestFunction):
    """Hartmann-3 on [0, 1]^3: four local minima, global −3.86278 at (0.114614, 0.555649, 0.852547)."""

    name = "hartmann3"
    variables = (Variable("x1", 0.0, 1.0), Variable("x2", 0.0, 1.0), Variable("x3", 0.0, 1.0))
    f_min = -3.86278214782076
    x_min = np.array([[0.114614, 0.555649, 0.852547]])
    f_second = -3.08976
    f_range = 3.8628  # dense_grid_range(Hartmann3(), 201): max −3.8e-5 (a corner) minus f_min
    range_grid = 201

    _A = np.array([[3.0, 10, 30], [0.1, 10, 35], [3.0, 10, 30], [0.1, 10, 35]])
    _C = np.array([1.0, 1.2, 3.0, 3.2])
    _P = 1e-4 * np.array([[3689, 1170, 2673], [4699, 4387, 7470], [1091, 8732, 5547], [381, 5743, 8828]])

    def function(self, X: np.ndarray) -> np.ndarray:
        inner = np.einsum("jk,njk->nj", self._A, (X[:, None, :] - self._P[None, :, :]) ** 2)
        return -np.exp(-inner) @ self._C


class CosineBowl3(TestFunction):
    """Σ (x − 0.3)² − 0.3 Π cos(3π (x − 0.3)) on [0, 1]^3: 31 local minima, global −0.3 at (0.3, 0.3, 0.3)."""

    name = "cosine_bowl3"
    variables = (Variable("x1", 0.0, 1.0), Variable("x2", 0.0, 1.0), Variable("x3", 0.0, 1.0))
    f_min = -0.3
    x_min = np.array([[0.3, 0.3, 0.3]])
    f_second = -0.0937
    f_range = 1.6726  # dense_grid_range(CosineBowl3(), 201): max 1.37258 minus f_min
    range_grid = 201

    def function(self, X: np.ndarray) -> np.ndarray:
        t = X - 0.3
        return np.sum(t * t, axis=1) - 0.3 * np.prod(np.cos(3.0 * np.pi * t), axis=1)


class Branin(TestFunction):
    """Branin on [−5, 10] × [0, 15]: three global minima 0.397887 (−π, 12.275), (π, 2.275), (9.42478, 2.475)."""

    name = "branin"
    variables = (Variable("x1", -5.0, 10.0), Variable("x2", 0.0, 15.0))
    f_min = 0.39788735772973816
    x_min = np.array([[-np.pi, 12.275], [np.pi, 2.275], [3 * np.pi, 2.475]])
    f_second = np.nan  # all three minima are global
    f_range = 307.73  # dense_grid_range(Branin(), 1501): max 308.1291 at (−5, 0) minus f_min
    range_grid = 1501

    def function(self, X: np.ndarray) -> np.ndarray:
        x1, x2 = X[:, 0], X[:, 1]
        b, c = 5.1 / (4 * np.pi**2), 5 / np.pi
        return (x2 - b * x1**2 + c * x1 - 6) ** 2 + 10 * (1 - 1 / (8 * np.pi)) * np.cos(x1) + 10


class SixHumpCamel(TestFunction):
    """Six-hump camel on [−3, 3] × [−2, 2]: six local minima, global −1.031628 at ±(0.089842, −0.712656)."""

    name = "six_hump_camel"
    variables = (Variable("x1", -3.0, 3.0), Variable("x2", -2.0, 2.0))
    f_min = -1.0316284534898774
    x_min = np.array([[0.0898420131, -0.7126564030], [-0.0898420131, 0.7126564030]])
    f_second = -0.215464
    f_range = 163.93  # dense_grid_range(SixHumpCamel(), 1501): max 162.9 at (±3, ±2) minus f_min
    range_grid = 1501

    def function(self, X: np.ndarray) -> np.ndarray:
        x1, x2 = X[:, 0], X[:, 1]
        return (4 - 2.1 * x1**2 + x1**4 / 3) * x1**2 + x1 * x2 + (-4 + 4 * x2**2) * x2**2


class HimmelblauDisc(TestFunction):
    """Himmelblau on [−5, 5]^2 with the margin 4.5 − |x| >= 0 (a disc): of its four minima (value 0), the one at
    (−3.779, −3.283) lies outside the disc; the other three are the global minima.
    """

    name = "himmelblau_disc"
    variables = (Variable("x1", -5.0, 5.0), Variable("x2", -5.0, 5.0))
    constraints = ("disc",)
    f_min = 0.0
    x_min = np.array([[3.0, 2.0], [-2.805118, 3.131312], [3.584428, -1.848126]])
    f_second = 8.3653  # constrained local minimum on the disc near (−3.444, −2.896), by SLSQP on the disc
    f_range = 418.63  # dense_grid_range(HimmelblauDisc(), 1501): max 418.628 on the disc, minus f_min
    range_grid = 1501
    radius = 4.5

    def margins(self, X: np.ndarray) -> np.ndarray:
        return (self.radius - np.hypot(X[:, 0], X[:, 1]))[:, None]

    def function(self, X: np.ndarray) -> np.ndarray:
        x1, x2 = X[:, 0], X[:, 1]
        return (x1**2 + x2 - 11) ** 2 + (x1 + x2**2 - 7) ** 2


def _axes(prefix: str, dim: int, lower: float, upper: float) -> tuple[Variable, ...]:
    return tuple(Variable(f"{prefix}{i + 1}", lower, upper) for i in range(dim))


def sampled_range(problem: TestFunction, n: int, seed: int = 0) -> tuple[float, float]:
    """Smallest and largest value found on ``n`` Sobol points, the 2^d corners and L-BFGS-B ascents from the 20
    highest points: the range of a function whose dimension forbids a dense grid (d >= 5).

    Parameters
    ----------
    problem : TestFunction
    n : int
        Sobol points (a power of 2 keeps the sequence balanced).
    seed : int
        Scrambling seed.

    Returns
    -------
    (float, float)
        min and max found.
    """
    from scipy.stats import qmc

    b = problem.bounds
    width = b[:, 1] - b[:, 0]
    U = qmc.Sobol(problem.dim, seed=seed).random(n)
    corners = np.array(np.meshgrid(*[[0.0, 1.0]] * problem.dim, indexing="ij")).reshape(problem.dim, -1).T
    U = np.vstack([U, corners])
    f = problem(b[:, 0] + U * width)
    for u0 in U[np.argsort(f)[-20:]]:
        res = minimize(lambda u: -float(problem(b[:, 0] + u * width)[0]), u0, method="L-BFGS-B",
                       bounds=[(0, 1)] * problem.dim)
        f = np.append(f, -res.fun)
    return float(f.min()), float(f.max())


class _Hartmann(TestFunction):
    """−Σ c_i exp(−Σ_j A_ij (x_j − P_ij)²) on [0, 1]^d with the 4 × 6 tables of Dixon & Szegő (1978)."""

    _A = np.array([[10, 3, 17, 3.5, 1.7, 8], [0.05, 10, 17, 0.1, 8, 14], [3, 3.5, 1.7, 10, 17, 8],
                   [17, 8, 0.05, 10, 0.1, 14]], dtype=float)
    _C = np.array([1.0, 1.2, 3.0, 3.2])
    _P = 1e-4 * np.array([[1312, 1696, 5569, 124, 8283, 5886], [2329, 4135, 8307, 3736, 1004, 9991],
                          [2348, 1451, 3522, 2883, 3047, 6650], [4047, 8828, 8732, 5743, 1091, 381]], dtype=float)

    def function(self, X: np.ndarray) -> np.ndarray:
        d = X.shape[1]
        A, P = self._A[:, :d], self._P[:, :d]
        inner = np.einsum("jk,njk->nj", A, (X[:, None, :] - P[None, :, :]) ** 2)
        return -np.exp(-inner) @ self._C


class Hartmann4(_Hartmann):
    """Hartmann-4 (the first four columns of Hartmann-6's tables) on [0, 1]^4: global −3.72984."""

    name = "hartmann4"
    variables = _axes("x", 4, 0.0, 1.0)
    f_min = -3.7298406  # L-BFGS-B from the 30 best of 20 000 random points
    x_min = np.array([[0.187395, 0.194152, 0.557918, 0.264780]])
    f_second = -3.5301  # the other minimum L-BFGS-B descents from 400 random starts end at
    f_range = 3.7285  # dense_grid_range(Hartmann4(), 61): max −1.30e-3 minus f_min
    range_grid = 61


class Hartmann6(_Hartmann):
    """Hartmann-6 on [0, 1]^6: six local minima, global −3.32237 at (0.20169, 0.15001, 0.47687, 0.27533, 0.31165,
    0.6573)."""

    name = "hartmann6"
    variables = _axes("x", 6, 0.0, 1.0)
    f_min = -3.322368011391339
    x_min = np.array([[0.20168952, 0.15001069, 0.47687398, 0.27533243, 0.31165162, 0.65730054]])
    f_second = -3.2032
    f_range = 3.3224  # sampled_range(Hartmann6(), 2**16): max −2.8e-8 minus f_min
    range_grid = 0


class CosineBowl4(TestFunction):
    """Σ (x − 0.3)² − 0.3 Π cos(3π (x − 0.3)) on [0, 1]^4 (CosineBowl3 in 4-D): global −0.3 at (0.3, ..., 0.3)."""

    name = "cosine_bowl4"
    variables = _axes("x", 4, 0.0, 1.0)
    f_min = -0.3
    x_min = np.array([[0.3, 0.3, 0.3, 0.3]])
    f_second = np.nan
    f_range = 2.1499  # dense_grid_range(CosineBowl4(), 61): max 1.84989 minus f_min
    range_grid = 61

    def function(self, X: np.ndarray) -> np.ndarray:
        t = X - 0.3
        return np.sum(t * t, axis=1) - 0.3 * np.prod(np.cos(3.0 * np.pi * t), axis=1)


class StyblinskiTang3(TestFunction):
    """Styblinski–Tang ½ Σ (x⁴ − 16 x² + 5 x) on [−5, 5]^3: 2^3 local minima, global −117.498 at x_i = −2.90353."""

    name = "styblinski_tang3"
    variables = _axes("x", 3, -5.0, 5.0)
    f_min = -117.49849711131336
    x_min = np.array([[-2.903534018185960] * 3])
    f_second = -103.35  # two coordinates at −2.9035, one at the other minimum 2.7468
    f_range = 492.50  # the maximum 375 at (5, 5, 5) minus f_min (the sum separates; checked on a 201^3 grid)
    range_grid = 201

    def function(self, X: np.ndarray) -> np.ndarray:
        return 0.5 * np.sum(X**4 - 16.0 * X**2 + 5.0 * X, axis=1)


class Rosenbrock6(TestFunction):
    """Rosenbrock Σ 100 (x_{i+1} − x_i²)² + (1 − x_i)² on [−5, 10]^6: a curved valley, global 0 at (1, ..., 1)."""

    name = "rosenbrock6"
    variables = _axes("x", 6, -5.0, 10.0)
    f_min = 0.0
    x_min = np.ones((1, 6))
    f_second = 3.9739  # the local minimum near (−0.99, 0.98, 0.97, 0.95, 0.90, 0.81) of d >= 4
    f_range = 4.3429e6  # sampled_range(Rosenbrock6(), 2**16): max 4 342 905
    range_grid = 0

    def function(self, X: np.ndarray) -> np.ndarray:
        return np.sum(100.0 * (X[:, 1:] - X[:, :-1] ** 2) ** 2 + (1.0 - X[:, :-1]) ** 2, axis=1)


class Levy8(TestFunction):
    """Levy on [−10, 10]^8: a ripple of sin² terms on a bowl, global 0 at (1, ..., 1)."""

    name = "levy8"
    variables = _axes("x", 8, -10.0, 10.0)
    f_min = 0.0
    x_min = np.ones((1, 8))
    f_second = np.nan
    f_range = 573.93  # sampled_range(Levy8(), 2**16): max 573.930
    range_grid = 0

    def function(self, X: np.ndarray) -> np.ndarray:
        w = 1.0 + (X - 1.0) / 4.0
        head = np.sin(np.pi * w[:, 0]) ** 2
        body = np.sum((w[:, :-1] - 1.0) ** 2 * (1.0 + 10.0 * np.sin(np.pi * w[:, :-1] + 1.0) ** 2), axis=1)
        tail = (w[:, -1] - 1.0) ** 2 * (1.0 + np.sin(2.0 * np.pi * w[:, -1]) ** 2)
        return head + body + tail


class Ackley8(TestFunction):
    """Ackley on [−10, 30]^8: a near-flat plateau of ripples around one funnel, global 0 at the origin.

    The box is shifted from the usual symmetric one so that no method finds the minimum by starting at the box's
    centre.
    """

    name = "ackley8"
    variables = _axes("x", 8, -10.0, 30.0)
    f_min = 0.0
    x_min = np.zeros((1, 8))
    f_second = np.nan
    f_range = 22.202  # sampled_range(Ackley8(), 2**14): max 22.2023
    range_grid = 0

    def function(self, X: np.ndarray) -> np.ndarray:
        rms = np.sqrt(np.mean(X * X, axis=1))
        return -20.0 * np.exp(-0.2 * rms) - np.exp(np.mean(np.cos(2.0 * np.pi * X), axis=1)) + 20.0 + np.e


class FailingHartmann3(Hartmann3):
    """Hartmann-3 whose simulator fails in part of the box: ``evaluate`` raises where x1 > 0.85 and returns NaN
    where x2 > 0.9 (the global minimum lies where it succeeds).

    A hidden constraint: nothing declares the failing region, a method learns it from the failures.  ``f_range``
    is Hartmann-3's over the succeeding part of the box.
    """

    name = "failing_hartmann3"
    f_range = 3.8626  # a 201^3 grid of the succeeding part: max −1.8e-4 minus f_min
    raise_above = 0.85
    nan_above = 0.9

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        """The function at one design, or a failure: RuntimeError where x1 > 0.85, NaN where x2 > 0.9."""
        if x[0] > self.raise_above:
            raise RuntimeError(f"simulation diverged at x1 = {x[0]:.3f}")
        if x[1] > self.nan_above:
            return {"f": float("nan")}
        return super().evaluate(x)


class NoisyHartmann6(Hartmann6):
    """Hartmann-6 simulated with numerical noise: ``evaluate`` adds noise of sd 1 % of the range, deterministic in
    the design and rough across designs (a time step, a mesh); the closed form (``function``) is noise-free.

    A benchmark scores a returned design by the closed form: the lowest value simulated is partly a lucky draw.
    """

    name = "noisy_hartmann6"
    #: The noise's standard deviation as a fraction of ``f_range``.
    noise = 0.01

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        """The function at one design plus its noise: a normal draw seeded by the design's bytes."""
        x = np.asarray(x, dtype=float)
        key = int.from_bytes(hashlib.sha256(np.round(x, 9).tobytes()).digest()[:8], "little")
        draw = float(np.random.default_rng(key).standard_normal())
        return {"f": super().evaluate(x)["f"] + self.noise * self.f_range * draw}


#: The benchmark suite, by name.
SUITE: dict[str, type[TestFunction]] = {
    cls.name: cls for cls in (Hartmann3, CosineBowl3, Branin, SixHumpCamel, HimmelblauDisc, Hartmann4, CosineBowl4,
                              StyblinskiTang3, FailingHartmann3, Hartmann6, NoisyHartmann6, Rosenbrock6, Levy8,
                              Ackley8)
}

# The valleys build on TestFunction and add themselves to SUITE; they live in their own module.
from mechopt.studies import valley_functions  # noqa: E402, F401
