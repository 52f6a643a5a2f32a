"""``mechopt dashboard``: serve the live page of a sample store (or a study's output folder) on 127.0.0.1."""

from __future__ import annotations

import argparse
import sys

__all__ = ["add_parser", "run"]


def _port(text: str) -> int:
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number (0 to 65535)") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"{port} is not a port number (0 to 65535)")
    return port


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not 0.2 <= value <= 3600:
        raise argparse.ArgumentTypeError(f"{value:g} s: expected 0.2 to 3600 seconds")
    return value


def add_parser(sub) -> None:
    """Add ``dashboard`` to the subcommands."""
    p = sub.add_parser("dashboard", help="a live page of a run in the browser (reads the sample store)",
                       description="Serve a page on 127.0.0.1 that shows the studies of a sample store while they "
                       "run and after they end: simulations done and planned, time left, best so far, every design "
                       "in parallel coordinates, failures, the front, the plan and the messages. It reads the store "
                       "only (read-only), refreshes by itself, and needs nothing from the internet.")
    p.add_argument("path", metavar="PATH", help="a sample store (.sqlite) or a study's output folder")
    p.add_argument("--port", type=_port, default=8050, help="TCP port on 127.0.0.1 (default 8050; 0: a free one)")
    p.add_argument("--refresh", type=_seconds, default=2.0, metavar="SECONDS",
                   help="seconds between the page's reads of the store (default 2)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace, rest: list[str]) -> int:
    """Serve the page until Ctrl-C or SIGTERM."""
    from mechopt.report.dashboard.server import DashboardServer

    server = DashboardServer(args.path, port=args.port, refresh_s=args.refresh)
    print(f"mechopt dashboard of {server.store} at {server.url} (Ctrl-C to stop)", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        print("mechopt dashboard: stopped", file=sys.stderr)
    finally:
        server.httpd.server_close()
    return 0
