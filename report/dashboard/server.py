"""The live page's HTTP server: one page, the plotly.js of the installed ``plotly`` package, and two JSON answers.

It listens on 127.0.0.1 only and reads the store read-only at each request the page makes (every few seconds);
answers are cached until the store changes.  Nothing is fetched from the internet: the page loads plotly.js from
this server, which reads it from the ``plotly`` package's own files.
"""

from __future__ import annotations

import errno
import json
import sqlite3
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib.resources import files
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlparse

from mechopt.errors import InputError
from mechopt.report.dashboard.store_reader import find_store, list_studies, open_read_only, read_study, store_version

__all__ = ["DashboardServer", "plotly_js"]

#: The only address the page is served on: the machine itself.
HOST = "127.0.0.1"


def plotly_js() -> Path:
    """The minified plotly.js inside the installed ``plotly`` package.

    Raises
    ------
    InputError
        If plotly is not installed (the ``dashboard`` extra).
    """
    try:
        import plotly
    except ImportError:
        raise InputError("mechopt dashboard needs plotly: pip install 'mechopt[dashboard]'") from None
    path = Path(plotly.__file__).parent / "package_data" / "plotly.min.js"
    if not path.is_file():
        raise InputError(f"the installed plotly {plotly.__version__} has no {path.name}; reinstall plotly")
    return path


def study_json(store: Path, fingerprint: str, objective: str | None, folder: Path | None = None) -> str:
    """The JSON the page draws for one study: its summary and its figures."""
    from mechopt.report.dashboard.figures import failures_figure, front_figure, parallel_figure, progress_figure
    from mechopt.report.dashboard.snapshot import snapshot

    conn = open_read_only(store)
    try:
        snap = snapshot(read_study(conn, fingerprint, folder), objective)
    finally:
        conn.close()
    figures = {"progress": progress_figure(snap), "parallel": parallel_figure(snap),
               "failures": failures_figure(snap), "front": front_figure(snap)}
    parts = ",".join(f'"{k}":{fig.to_json() if fig is not None else "null"}' for k, fig in figures.items())
    head = {"name": snap.name, "fingerprint": snap.fingerprint, "objectives": snap.objectives,
            "outputs": snap.outputs, "summary": snap.summary}
    return f'{{"study":{json.dumps(head, default=float)},"figures":{{{parts}}}}}'


class DashboardServer:
    """Serve the live page of a store (or a study's output folder) on 127.0.0.1.

    Parameters
    ----------
    path : str or Path
        A sample store, or a study's output folder.
    port : int
        TCP port; 0 picks a free one.
    refresh_s : float
        Seconds between the page's reads of the store.

    Raises
    ------
    InputError
        One line: no store at ``path``, not a store, or the port taken.
    """

    def __init__(self, path: str | Path, port: int = 8050, refresh_s: float = 2.0) -> None:
        self.store = find_store(path)
        #: The output folder named on the command line, for the result.json of runs that left no journal.
        self.folder = Path(path) if Path(path).is_dir() else None
        open_read_only(self.store).close()
        self.js = plotly_js()
        page = files("mechopt.report.dashboard").joinpath("page.html").read_text(encoding="utf-8")
        self.page = page.replace("{{REFRESH_MS}}", str(int(refresh_s * 1000))).replace("{{STORE}}", str(self.store))
        self._cache: dict[tuple, tuple[tuple, str]] = {}
        self._lock = threading.Lock()
        try:
            self.httpd = ThreadingHTTPServer((HOST, int(port)), _handler(self))
        except OSError as exc:
            if exc.errno == errno.EADDRINUSE:
                raise InputError(f"--port {port}: the port is in use; give another (or 0 for a free one)") from None
            raise InputError(f"--port {port}: cannot listen on {HOST}: {exc.strerror or exc}") from None
        self.httpd.daemon_threads = True

    @property
    def url(self) -> str:
        """The page's address."""
        return f"http://{HOST}:{self.httpd.server_address[1]}/"

    def studies(self) -> str:
        """The JSON list of the store's studies."""
        conn = open_read_only(self.store)
        try:
            return json.dumps({"store": str(self.store), "studies": list_studies(conn, self.folder)})
        finally:
            conn.close()

    def study(self, fingerprint: str, objective: str | None) -> str:
        """One study's JSON, computed again only when the store changed."""
        conn = open_read_only(self.store)
        try:
            version = store_version(conn)
        finally:
            conn.close()
        key = (fingerprint, objective)
        with self._lock:
            cached = self._cache.get(key)
        if cached is not None and cached[0] == version:
            return cached[1]
        body = study_json(self.store, fingerprint, objective, self.folder)
        with self._lock:
            self._cache[key] = (version, body)
        return body

    def serve_forever(self) -> None:
        """Serve until :meth:`shutdown` (or Ctrl-C in the caller)."""
        self.httpd.serve_forever(poll_interval=0.2)

    def shutdown(self) -> None:
        """Stop serving and close the socket."""
        self.httpd.shutdown()
        self.httpd.server_close()


def _handler(server: DashboardServer) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 (the name http.server calls)
            url = urlparse(self.path)
            query = {k: v[0] for k, v in parse_qs(url.query).items()}
            try:
                if url.path == "/":
                    self._send(server.page.encode(), "text/html; charset=utf-8")
                elif url.path == "/favicon.ico":
                    self._send(b"", "image/x-icon", cache=True, status=204)
                elif url.path == "/plotly.min.js":
                    self._send(server.js.read_bytes(), "text/javascript", cache=True)
                elif url.path == "/api/studies":
                    self._send(server.studies().encode(), "application/json")
                elif url.path == "/api/study" and "fp" in query:
                    self._send(server.study(query["fp"], query.get("objective")).encode(), "application/json")
                else:
                    self.send_error(404)
            except (InputError, sqlite3.Error) as exc:
                # The page says it and asks again at its next refresh (a store being replaced, a locked file).
                self._send(json.dumps({"error": " ".join(str(exc).split())}).encode(), "application/json",
                           status=503)

        def _send(self, body: bytes, kind: str, cache: bool = False, status: int = 200) -> None:
            self.send_response(status)
            self.send_header("Content-Type", kind)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "max-age=86400" if cache else "no-store")
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args: Any) -> None:
            pass  # the page asks every few seconds: no line per request

    return Handler
