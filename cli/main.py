"""The ``mechopt`` command line: the parser, and the dispatch to one module per command.

Exit status: 0 success; 1 a user error (bad input, unknown study, malformed TOML, an unwritable output), printed as
one line on stderr; 2 a malformed command line; 3 for ``simulate`` when the design is infeasible (the answer is
still printed: which constraint fails, by how much); 130 when interrupted (Ctrl-C) and 143 when terminated (SIGTERM:
``kill``, ``timeout``, a batch scheduler's stop), with every finished simulation kept in the store.
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Sequence

from mechopt.cli import (
    catalogue_commands,
    compare_command,
    dashboard_command,
    region_commands,
    simulate_command,
    study_command,
    tolerance_command,
    validate_command,
)
from mechopt.cli.arguments import Parser
from mechopt.cli.simulate_command import EXIT_INFEASIBLE
from mechopt.errors import MechoptError
from mechopt.surrogate.errors import SurrogateError

__all__ = ["EXIT_ERROR", "EXIT_INFEASIBLE", "EXIT_INTERRUPTED", "EXIT_TERMINATED", "build_parser", "main"]

EXIT_ERROR = 1
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143
KEPT = "every simulation finished so far is kept in the store"


class _Terminated(KeyboardInterrupt):
    """SIGTERM, raised where a Ctrl-C would be.

    Python's default for SIGTERM ends the process on the spot: the run's claims on the designs in progress stay in
    the store, the workers are left to notice, and the only output was multiprocessing's warning of leaked
    semaphores.  As a KeyboardInterrupt it takes the interrupt's way out: claims released, programs in progress
    stopped, one line.
    """


def _raise_terminated(_signum: int, _frame: object) -> None:
    raise _Terminated


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``mechopt`` with all its subcommands."""
    from mechopt import __version__
    from mechopt.sim.four_bar.simulate import ENGINES

    parser = Parser(prog="mechopt",
                    description="Globally optimal mechanism dimensions from few motion simulations (lengths in mm).")
    parser.add_argument("--version", action="version", version=f"mechopt {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    catalogue_commands.add_parsers(sub)
    simulate_command.add_parser(sub, ENGINES)
    study_command.add_parser(sub, ENGINES)
    validate_command.add_parser(sub, ENGINES)
    region_commands.add_parsers(sub, ENGINES)
    compare_command.add_parser(sub, ENGINES)
    tolerance_command.add_parser(sub, ENGINES)
    dashboard_command.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``mechopt``; returns the exit status (see the module docstring)."""
    parser = build_parser()
    args, rest = parser.parse_known_args(argv)
    if rest and not getattr(args, "extra", False):
        parser.error(f"unrecognized arguments: {' '.join(rest)}")
    try:
        previous = signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:  # not the main thread (main() called from a thread): leave SIGTERM as it is
        previous = None
    try:
        return int(args.func(args, rest))
    except (MechoptError, SurrogateError) as exc:
        print(f"mechopt: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except _Terminated:
        print(f"mechopt: terminated (SIGTERM); {KEPT}", file=sys.stderr)
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        print(f"mechopt: interrupted; {KEPT}", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    sys.exit(main())
