"""The design-problem protocol: what mechopt needs to know of a mechanism, a study or a user's own simulator.

A problem is a small class, in the manner of SMT's ``Problem``: it declares its design variables (name, bounds,
unit), its constraints as named, vectorised margins (>= 0 feasible), the outputs its evaluator returns for one
design, the objective (one of those outputs, and whether the sparse model fits it or its square) and the settings
that change an output (hashed into the fingerprint that keys the sample store).  Everything else — planning lines,
sampling through the store, fitting, searching, refining, validating, reporting — is mechopt's and works for any
problem with 2 to 4 variables.

Example
-------
>>> import numpy as np, mechopt
>>> class Bowl(mechopt.DesignProblem):
...     name = "bowl"
...     variables = (mechopt.Variable("a", 0.0, 2.0), mechopt.Variable("b", 0.0, 2.0))
...     constraints = ("disc",)
...     outputs = ("f",)
...     objective = "f"
...     def margins(self, X):
...         return (1.5**2 - X[:, 0] ** 2 - X[:, 1] ** 2)[:, None]
...     def evaluate(self, x):
...         return {"f": 1.0 + (x[0] - 1.0) ** 2 + (x[1] - 0.5) ** 2}
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from mechopt.errors import InputError, MechoptError
from mechopt.optimize.allowed_designs import AllowedDesigns
from mechopt.optimize.objectives import DeclaredObjectives
from mechopt.optimize.variable import MIN_SPAN, Variable
from mechopt.runs.fingerprint import fingerprint

__all__ = ["FITS", "MIN_SPAN", "DesignProblem", "Variable", "as_design_array"]

#: What the sparse model fits along its lines: the objective itself, or its square (smoother for an RMS value).
FITS = ("value", "square")


#: Designs :meth:`DesignProblem.check_region` spreads over the box to find a feasible one.
REGION_PROBES = 2**14

def as_design_array(X: Any, dim: int, what: str = "designs") -> np.ndarray:
    """Validate designs and return them as a float array of shape (n, dim).

    Parameters
    ----------
    X : array_like
        One design (dim,) or several (n, dim).
    dim : int
        Number of design variables.
    what : str
        Name used in the error message.

    Raises
    ------
    InputError
        Wrong shape or a non-finite value.
    """
    try:
        arr = np.array(X, dtype=float, ndmin=2)
    except (TypeError, ValueError):
        raise InputError(f"{what} must be numbers, got {X!r:.80}") from None
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise InputError(f"{what} must have {dim} values per design, got shape {np.shape(X)}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{what} must be finite, got {arr[~np.all(np.isfinite(arr), axis=1)][0].tolist()}")
    return arr


class DesignProblem(DeclaredObjectives, AllowedDesigns):
    """Base class of every design problem (a mechanism study, a test function, a user's simulator).

    Subclasses set the class attributes (or instance attributes in ``__init__``) and implement :meth:`evaluate`,
    and :meth:`margins` when there are constraints.  Instances must be picklable (a class defined at the top
    level of a module) to be evaluated in worker processes or on Dask.

    Attributes
    ----------
    name : str
        Name of the problem (reports, the store's fingerprint).
    variables : tuple of Variable
        The design variables, 2 to 4 of them for the sparse method.
    constraints : tuple of str
        Names of the columns of :meth:`margins`.
    outputs : tuple of str
        Names of the outputs :meth:`evaluate` must return (finite floats); it may return more keys.
    objective : str or tuple of str
        The output minimised, or 1 to 4 of them (a Pareto front); a leading ``-`` maximises an output
        (:mod:`mechopt.optimize.objectives`).
    limits : dict
        ``{output: (lower, upper)}``, either bound None, in the output's unit: a simulated design outside is kept
        in the store and infeasible in every answer.
    ideal, nadir : array_like, optional
        Not declared by default.  A problem with several objectives may give the least and the largest value of
        each minimised objective over its front (as the test problems of
        :mod:`~mechopt.studies.multi_objective_functions` do): the result's hypervolume is then normalised by them,
        and the default method's search measures its proposals on the same scale.  Give them only when they are
        the front's known bounds: a loose guess measured worse than none (``docs/guide/trade_offs.md``).
    fit : str
        ``"square"`` (the model fits the objective squared, as T_RMS² for an RMS torque) or ``"value"``.
    output_units : dict
        Unit of each output, for reports and axis labels (``{"t_rms": "N·m"}``).
    version : int
        Bump it when :meth:`evaluate` changes in a way :meth:`settings` does not show, so that stored samples of
        the old code are not reused.
    surrogate_order : tuple of int or None
        Order of the variables in the sparse model's coordinates (paper 002 plans the ventilator over
        (|OA|, |BC|, |AB|)); None keeps the declared order.
    fd_step : float
        Finite-difference step of local searches on the simulator, as a fraction of each variable's range: above
        the simulator's noise (a time-stepping engine: 1e-3), as small as the arithmetic allows for a smooth,
        closed-form one (1e-5, the default).
    residuals : str
        A least-squares problem names here the output of :meth:`evaluate` that holds its residual vector (a list
        of floats); its objective must be zero exactly where the residuals are (a sum of squares, or a sum of RMS
        terms).  The methods' local phases then take Gauss-Newton steps on the residuals
        (:mod:`mechopt.optimize.least_squares`).  Empty (default): a plain scalar objective.
    """

    name: ClassVar[str] | str = "problem"
    variables: tuple[Variable, ...] = ()
    constraints: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    objective: str | tuple[str, ...] = ""
    limits: dict[str, tuple[float | None, float | None]] = {}  # noqa: RUF012 - read-only class default
    fit: str = "value"
    output_units: dict[str, str] = {}  # noqa: RUF012 - read-only class default
    version: int = 1
    surrogate_order: tuple[int, ...] | None = None
    fd_step: float = 1e-5
    residuals: str = ""

    # --- to implement -------------------------------------------------------------------------------------------

    def evaluate(self, x: np.ndarray) -> dict[str, float]:
        """Simulate one design.

        Parameters
        ----------
        x : (d,) ndarray
            The design, in the variables' units.

        Returns
        -------
        dict
            At least every name of :attr:`outputs`, as finite floats; further JSON-able keys are stored too.

        Raises
        ------
        InfeasibleDesignError
            When the design cannot be simulated at all (it does not assemble, it cannot move); recorded as
            ``infeasible``.  Any other exception is recorded as a failure of that design.
        """
        raise NotImplementedError(f"{type(self).__name__} must implement evaluate(x)")

    def margins(self, X: np.ndarray) -> np.ndarray:
        """Constraint margins of designs, vectorised: >= 0 where satisfied.

        Parameters
        ----------
        X : (n, d) ndarray
            Designs.

        Returns
        -------
        (n, len(constraints)) ndarray
            One column per name of :attr:`constraints`, in the constraint's own unit (mm, deg...).
        """
        return np.zeros((np.shape(X)[0], 0))

    def settings(self) -> dict[str, Any]:
        """Every setting that changes an output: engine, tables, physical constants, feasibility rules.

        Returns
        -------
        dict
            JSON-like; hashed into :meth:`fingerprint`.  The default is empty (then bump :attr:`version` when the
            evaluator changes).
        """
        return {}

    # --- optional ------------------------------------------------------------------------------------------------

    def sampleable(self, X: np.ndarray) -> np.ndarray:
        """Designs that may be simulated to build the model (default: the feasible ones).

        A mechanism can often be simulated a little beyond its design rules (a toggle margin, a box face that is a
        choice and not physics); lines that run on there span the feasible region's whole extent, so the line
        models do not extrapolate inside it.  Plain bounds of a user's simulator are not crossed by default.
        """
        return self.feasible(X)

    def screen(self, X: np.ndarray) -> np.ndarray:
        """A cheaper feasibility test for search grids of millions of points (default: :meth:`feasible`).

        The design finally reported is always checked with :meth:`feasible`.
        """
        return self.feasible(X)

    def describe(self, x: np.ndarray) -> str:
        """One line naming a design with units, e.g. ``oa=53.000 mm, ab=65.000 mm``."""
        return ", ".join(f"{v.name}={float(xi):.4g}{(' ' + v.unit) if v.unit else ''}"
                         for v, xi in zip(self.variables, np.ravel(x), strict=True))

    def figures(self, designs: Mapping[str, np.ndarray], out: Path) -> dict[str, Path]:
        """Mechanism-specific figures of named designs (drawings, time series, animation); default none.

        Parameters
        ----------
        designs : mapping of str to (d,) ndarray
            ``{"original": x0, "optimum": x*, ...}``.
        out : Path
            Folder to write PNG/GIF files into.

        Returns
        -------
        dict
            Caption -> file written.
        """
        return {}

    # --- provided ------------------------------------------------------------------------------------------------

    @property
    def dim(self) -> int:
        """Number of design variables d."""
        return len(self.variables)

    @property
    def names(self) -> tuple[str, ...]:
        """Variable names in order."""
        return tuple(v.name for v in self.variables)

    @property
    def bounds(self) -> np.ndarray:
        """(d, 2) array of the variables' lower and upper bounds."""
        return np.array([[v.lower, v.upper] for v in self.variables], dtype=float)

    def in_box(self, X: np.ndarray, extend: float = 0.0) -> np.ndarray:
        """Designs (n, d) inside the bounds, widened by ``extend`` times the width on each side."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        b = self.bounds
        w = b[:, 1] - b[:, 0]
        return np.all((X >= b[:, 0] - extend * w) & (X <= b[:, 1] + extend * w), axis=1)

    def constraint_margins(self, X: Any) -> np.ndarray:
        """:meth:`margins` with its input and output checked: (n, len(constraints)), NaN read as violated."""
        X = as_design_array(X, self.dim)
        try:
            M = np.asarray(self.margins(X), dtype=float)
        except MechoptError:
            raise
        except Exception as exc:  # the user's code: one line naming it, not a traceback from inside a method
            raise InputError(f"{self.name}: margins raised {type(exc).__name__}: {exc}") from None
        if M.ndim == 1 and len(self.constraints) == 1:
            M = M[:, None]
        if M.shape != (X.shape[0], len(self.constraints)):
            raise InputError(f"{self.name}: margins returned shape {M.shape}, expected "
                             f"({X.shape[0]}, {len(self.constraints)}) for constraints {list(self.constraints)}")
        return np.where(np.isnan(M), -np.inf, M)

    def check_region(self, n: int = REGION_PROBES) -> None:
        """Raise a one-line :class:`InputError` if no design of ``n`` spread over the box (a scrambled Sobol set,
        fixed seed) satisfies the declared constraints: no method can start, and each would fail its own way."""
        if not self.constraints:
            return
        from scipy.stats import qmc

        b = self.bounds
        X = b[:, 0] + qmc.Sobol(self.dim, seed=0).random(n) * (b[:, 1] - b[:, 0])
        M = self.constraint_margins(X)
        if np.all(M >= 0.0, axis=1).any():
            return
        best = ", ".join(f"{c} {m:.3g}" if np.isfinite(m) else f"{c} NaN everywhere"
                         for c, m in zip(self.constraints, M.max(axis=0), strict=True))
        raise InputError(f"problem {self.name!r}: none of {n} designs spread over the box satisfies the declared "
                         f"constraints (largest margins: {best}); expected some design with every margin >= 0: "
                         "check the bounds and the margins' signs")

    def feasible(self, X: Any, margins: np.ndarray | None = None) -> np.ndarray:
        """Designs (n, d) inside the bounds and satisfying every constraint.

        ``margins``: :meth:`constraint_margins` of all of X, when the caller has them already (a figure that also
        draws each constraint's contour); otherwise they are computed for the designs inside the bounds only.
        """
        X = as_design_array(X, self.dim)
        ok = self.in_box(X)
        if len(self.constraints) and ok.any():
            if margins is None:
                M = self.constraint_margins(X[ok])
            else:
                M = np.asarray(margins, dtype=float)
                if M.shape != (X.shape[0], len(self.constraints)):
                    raise InputError(f"{self.name}: margins of shape {M.shape} given for {X.shape[0]} designs; "
                                     f"expected ({X.shape[0]}, {len(self.constraints)}), one column a constraint")
                M = M[ok]
            ok[ok] = np.all(M >= 0.0, axis=1)
        return ok

    def output_label(self, name: str) -> str:
        """``name (unit)`` of an output, for tables and axes."""
        unit = dict(self.output_units).get(name, "")
        return f"{name} ({unit})" if unit else name

    def objective_value(self, outputs: Mapping[str, float]) -> float:
        """The (first) objective from an evaluation's outputs, as minimised (a maximised output negated)."""
        return float(self.objective_spec.values(outputs)[0])

    def residual_vector(self, outputs: Mapping[str, Any]) -> np.ndarray:
        """The residual vector of an evaluation's outputs (a least-squares problem; :attr:`residuals`).

        Raises
        ------
        InputError
            The problem declares no residuals, or the output is missing or not a flat list of finite numbers.
        """
        if not self.residuals:
            raise InputError(f"problem {self.name!r} declares no residuals (set its `residuals` attribute)")
        try:
            r = np.asarray(outputs[self.residuals], dtype=float)
        except KeyError:
            raise InputError(f"problem {self.name!r}: evaluate() returned no {self.residuals!r} "
                             f"(its declared residuals)") from None
        if r.ndim != 1 or not r.size or not np.all(np.isfinite(r)):
            raise InputError(f"problem {self.name!r}: output {self.residuals!r} must be a non-empty flat list of "
                             f"finite numbers, got shape {r.shape}")
        return r

    def fingerprint(self) -> str:
        """Hash of the problem's identity and :meth:`settings` (the key of its rows in the sample store)."""
        return fingerprint({
            "problem": f"{type(self).__module__}.{type(self).__qualname__}",
            "name": self.name,
            "version": self.version,
            "variables": [v.name for v in self.variables],
            "outputs": list(self.outputs),
            "settings": self.settings(),
        })

    def check(self) -> None:
        """Raise a one-line :class:`InputError` if the declaration is inconsistent (called before any work)."""
        where = f"problem {self.name!r}"
        if not self.variables or not all(isinstance(v, Variable) for v in self.variables):
            raise InputError(f"{where}: variables must be a non-empty tuple of mechopt.Variable")
        if len(set(self.names)) != len(self.names):
            raise InputError(f"{where}: variable names {list(self.names)} are not distinct")
        for key in ("outputs", "constraints"):
            names = getattr(self, key)
            if isinstance(names, str) or not all(isinstance(n, str) for n in names):
                raise InputError(f"{where}: {key} = {names!r}; expected a tuple of names such as ('f',)")
        if not self.outputs:
            raise InputError(f"{where}: outputs = {self.outputs!r}; expected the names the evaluator returns")
        self.objective_spec  # noqa: B018 - parsing raises the one-line error
        self.limit_spec  # noqa: B018
        if not isinstance(self.residuals, str) or (self.residuals and not self.residuals.isidentifier()):
            raise InputError(f"{where}: residuals = {self.residuals!r}; expected the name of an output or ''")
        if self.fit not in FITS:
            raise InputError(f"{where}: fit = {self.fit!r}; expected one of {', '.join(FITS)}")
        order = self.surrogate_order
        if order is not None and sorted(order) != list(range(self.dim)):
            raise InputError(f"{where}: surrogate_order {order!r} must be a permutation of 0..{self.dim - 1}")

    def design_dict(self, x: Sequence[float]) -> dict[str, float]:
        """``{name: value}`` of a design."""
        return {v.name: float(xi) for v, xi in zip(self.variables, np.ravel(x), strict=True)}

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}: {', '.join(self.names)} -> {self.objective}>"
