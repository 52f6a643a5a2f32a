"""mechopt: globally optimal mechanism dimensions from a few hundred motion simulations.

The method is that of Ben Yahya et al. (2023, paper 002): simulate designs, bound the design space by feasibility,
sample the objective on parallel lines, fit each line with a sum of exponentials, blend the line models by Chebyshev
interpolation, search the blend exhaustively, refine on the simulator and validate on held-out simulations.

Public API (flat, as scipy.optimize and pymunk):

- :class:`DesignProblem`, :class:`Variable` — declare a problem: variables, constraint margins, evaluator, objective;
- :func:`minimize` -> :class:`OptimizeResult` — the sparse method or any baseline, within a simulation budget;
- :func:`load_study`, :func:`available_studies` — the studies shipped with mechopt (and yours, as TOML files);
- :class:`SparseOptions` — the sparse method's declared options (``SparseOptions.help()``);
- :class:`SampleStore` — the resumable SQLite store of simulated designs;
- :class:`ObjectiveModel` — a fitted sparse model (``.predict``, ``.save``, ``.load``);
- :func:`register_mechanism` — add a mechanism kind for study files;
- errors: :class:`MechoptError` and its subclasses :class:`InputError`, :class:`StudyError`,
  :class:`InfeasibleDesignError`.

Subpackages: :mod:`mechopt.sim` (the physics: one folder per mechanism), :mod:`mechopt.surrogate` (the mathematics,
independent of the physics), :mod:`mechopt.optimize` (the problem protocol, the table of methods and the methods),
:mod:`mechopt.runs` (the sample store, claims and executors), :mod:`mechopt.studies` (the shipped studies, the
study-file loader, the runner of a whole study, its plan and the optimizer comparison), :mod:`mechopt.report` (what
a run leaves for a person: result.json, report.md, figures) and :mod:`mechopt.cli` (the command line: it parses,
calls the library and prints).
"""

# pytest imports the checkout's root __init__.py as a plain file (no parent package) when the clone's folder name is
# not a valid module name (e.g. /tmp/tmp.XYZ); then there is nothing to set up.
if __package__:
    from mechopt._numba_cache import use_user_cache

    use_user_cache()

    from mechopt.errors import InfeasibleDesignError, InputError, MechoptError, StudyError

__version__ = "0.2.0"

# The rest of the API is imported on first use (PEP 562): every worker process and every CLI call imports mechopt,
# and the optimizers behind minimize() (scipy.stats, the baselines) cost seconds that a simulation does not need.
_LAZY = {
    "DesignProblem": "mechopt.optimize.problem",
    "Variable": "mechopt.optimize.problem",
    "minimize": "mechopt.optimize.minimize",
    "OptimizeResult": "mechopt.optimize.result",
    "load_study": "mechopt.studies.catalogue",
    "available_studies": "mechopt.studies.catalogue",
    "SparseOptions": "mechopt.optimize.sparse.options",
    "ObjectiveModel": "mechopt.optimize.sparse.model",
    "SampleStore": "mechopt.runs.store",
    "register_mechanism": "mechopt.studies.registry",
}

__all__ = [  # noqa: RUF022 - the eager names first, then the lazy ones
    "InfeasibleDesignError",
    "InputError",
    "MechoptError",
    "StudyError",
    "DesignProblem",
    "Variable",
    "minimize",
    "OptimizeResult",
    "load_study",
    "available_studies",
    "SparseOptions",
    "ObjectiveModel",
    "SampleStore",
    "register_mechanism",
]


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'mechopt' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
