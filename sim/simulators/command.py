"""An external program as the simulator: one process per design, the design in as JSON, the outputs back as JSON.

The program is started from an argv list (never through a shell) in a new process group (session), with the
environment of mechopt plus the study's ``env``.  The design goes in as one JSON object, ``{"oa": 53.0, ...,
"units": {"oa": "mm", ...}}``, on stdin (``exchange = "stdio"``) or as ``design.json`` in a per-design work folder
(``exchange = "files"``); the outputs come back as one JSON object, the whole of stdout or its last non-empty line
(``stdio``) or ``outputs.json`` in that folder (``files``).  ``{"infeasible": "reason"}`` says the design cannot be
simulated.

Every way the program can fail — a non-zero exit, a signal, a timeout, no or unparsable output, a missing or
non-finite output — raises :class:`~mechopt.sim.simulators.outputs.SimulatorFailure` with the exit code and the last
lines of stderr on one line; the sampler records it as a failed design and the run goes on.

On a timeout the whole process group is killed (the program and whatever it started), and after every call any
member of the group still alive is killed too.  On Linux the program also gets ``PR_SET_PDEATHSIG = SIGKILL``: it dies
with the worker process that started it, even when that worker is killed with ``kill -9`` (its own children, if it
moves them out of its group, are beyond reach).
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mechopt.sim.simulators.outputs import SimulatorFailure, checked_outputs, file_digest, resolve_entry, text_digest

__all__ = ["EXCHANGES", "KEEP", "CommandSimulator"]

#: How the design and outputs travel: through the pipes, or as files in a per-design work folder.
EXCHANGES = ("stdio", "files")
#: Which per-design work folders are kept after the call: all of them, or only those of failed designs.
KEEP = ("failed", "all")

_STDERR_LINES = 3
_STDERR_CHARS = 300
_PR_SET_PDEATHSIG = 1


def _libc_prctl() -> Any:
    if not sys.platform.startswith("linux"):
        return None
    try:
        prctl = ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None
    prctl.argtypes = (ctypes.c_int, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong)
    prctl.restype = ctypes.c_int
    return prctl


# Looked up once here: between fork and exec the child should do as little as possible (no dlopen, no imports).
_PRCTL = _libc_prctl()


def _die_with_parent(parent_pid: int) -> Any:
    """The child's set-up between fork and exec: SIGKILL it when the process that started it dies."""
    prctl = _PRCTL

    def setup() -> None:
        prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        if os.getppid() != parent_pid:  # the parent died before prctl took effect
            os._exit(1)

    return setup if prctl is not None else None


def _kill_group(pgid: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pgid, signal.SIGKILL)


def _stderr_tail(data: bytes) -> str:
    lines = [line.strip() for line in data.decode("utf-8", "replace").splitlines() if line.strip()]
    text = " | ".join(lines[-_STDERR_LINES:])
    return text if len(text) <= _STDERR_CHARS else "…" + text[-(_STDERR_CHARS - 1):]


def _parse_object(text: str) -> Any:
    """The JSON object of a simulator's output: the whole text, else its last non-empty line (after log lines)."""
    text = text.strip()
    try:
        return json.loads(text)
    except ValueError:
        pass
    lines = text.splitlines()
    if lines:
        try:
            return json.loads(lines[-1])
        except ValueError:
            pass
    shown = " ".join(text.split())
    raise ValueError(f"{shown[:80]!r}" + ("…" if len(shown) > 80 else "") if shown else "nothing")


@dataclass(frozen=True)
class CommandSimulator:
    """Run an external program once per design.

    Parameters
    ----------
    argv : tuple of str
        The command as written in the study file; ``{python}`` stands for the interpreter running mechopt and
        ``{study}`` for the study file's folder; an entry naming a file beside the study file is passed as an absolute
        path.
    outputs : tuple of str
        The outputs the program must return (finite numbers).
    folder : str
        The study file's folder (absolute): relative paths are read from there, and the program runs there when it
        has no per-design work folder.
    timeout_s : float
        Seconds a call may take before its process group is killed (the design is then a recorded failure).
    exchange : str
        ``"stdio"`` or ``"files"`` (see the module docstring).
    workdir : str, optional
        Folder (absolute) for the per-design work folders ``design-<hash>``: with ``files`` it defaults to
        ``mechopt-runs`` in the system's temporary folder; with ``stdio`` the program gets one only when it is set.
    env : tuple of (str, str)
        Variables added to the environment of the program.
    keep : str
        ``"failed"`` (default): a design's work folder is removed after a successful call; ``"all"``: kept.
    """

    argv: tuple[str, ...]
    outputs: tuple[str, ...]
    folder: str
    timeout_s: float = 3600.0
    exchange: str = "stdio"
    workdir: str | None = None
    env: tuple[tuple[str, str], ...] = ()
    keep: str = "failed"

    def settings(self) -> dict[str, Any]:
        """What changes the outputs: the argv as written, the contents of every entry that is a file (the user's
        script, the solver), the exchange mode and the environment (values hashed: they may be licence keys).
        The timeout and the work folder do not change an output that is returned."""
        files = {}
        for entry in self.argv:
            if "{python}" in entry:
                continue  # the interpreter: a property of the machine, not of the simulator
            path = resolve_entry(entry, self.folder)
            if os.path.isfile(path):
                files[entry] = file_digest(path)
        return {"command": list(self.argv), "files_sha256": files, "exchange": self.exchange,
                "env_sha256": {k: text_digest(v) for k, v in self.env}}

    def work_folder(self, design: Mapping[str, float]) -> Path | None:
        """The per-design work folder (None when the program runs in the study folder)."""
        if self.exchange == "stdio" and self.workdir is None:
            return None
        root = Path(self.workdir) if self.workdir else Path(tempfile.gettempdir()) / "mechopt-runs"
        key = json.dumps({k: float(v) for k, v in design.items()}, sort_keys=True)
        return root / f"design-{hashlib.sha256(key.encode()).hexdigest()[:16]}"

    def run(self, design: Mapping[str, float], units: Mapping[str, str] | None = None) -> dict[str, Any]:
        """Simulate one design.

        Parameters
        ----------
        design : mapping of str to float
            The design by variable name, in the variables' units.
        units : mapping of str to str, optional
            The unit of each variable (sent as ``"units"``).

        Returns
        -------
        dict
            Every declared output as a float, plus whatever else the program returned.

        Raises
        ------
        InfeasibleDesignError
            The program returned ``{"infeasible": reason}``.
        SimulatorFailure
            Any failure, with the exit code and the last lines of stderr.
        """
        payload = json.dumps({**{k: float(v) for k, v in design.items()}, "units": dict(units or {})})
        folder = self._prepare_work_folder(design, payload)
        returncode, out, err = self._execute(payload, folder)
        outputs = self._read_outputs(returncode, out, err, folder)
        if folder is not None and self.keep == "failed":
            shutil.rmtree(folder, ignore_errors=True)
        return outputs

    def _prepare_work_folder(self, design: Mapping[str, float], payload: str) -> Path | None:
        """Create the design's work folder afresh (with ``design.json`` for ``files``); None when there is none."""
        folder = self.work_folder(design)
        if folder is not None:
            if folder.exists():
                shutil.rmtree(folder, ignore_errors=True)  # an earlier attempt's leftovers must not pass for outputs
            try:
                folder.mkdir(parents=True, exist_ok=True)
                if self.exchange == "files":
                    (folder / "design.json").write_text(payload)
            except OSError as exc:
                raise SimulatorFailure(f"cannot prepare the work folder {folder}: {exc.strerror or exc}") from None
        return folder

    def _execute(self, payload: str, folder: Path | None) -> tuple[int, bytes, bytes]:
        """Run the program to its end (or kill its group on the timeout); its exit code, stdout and stderr."""
        argv = [resolve_entry(entry, self.folder) for entry in self.argv]
        env = {**os.environ, **dict(self.env)}
        stdin = subprocess.PIPE if self.exchange == "stdio" else subprocess.DEVNULL
        try:
            proc = subprocess.Popen(argv, cwd=str(folder or self.folder), env=env, stdin=stdin,
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
                                    preexec_fn=_die_with_parent(os.getpid()))
        except OSError as exc:
            raise SimulatorFailure(f"cannot start {argv[0]!r}: {exc.strerror or exc}") from None
        try:
            try:
                out, err = proc.communicate(payload.encode() if stdin is subprocess.PIPE else None,
                                            timeout=self.timeout_s)
            except subprocess.TimeoutExpired:
                _kill_group(proc.pid)
                out, err = proc.communicate()
                raise SimulatorFailure(f"timed out after {self.timeout_s:g} s (process group killed); stderr: "
                                       f"{_stderr_tail(err) or '(empty)'}") from None
        finally:
            _kill_group(proc.pid)  # whatever the program left running in its group
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        return proc.returncode, out, err

    def _read_outputs(self, returncode: int, out: bytes, err: bytes, folder: Path | None) -> dict[str, Any]:
        """Keep the program's stdout and stderr in its work folder; its checked outputs, or the failure raised."""
        if folder is not None:
            with contextlib.suppress(OSError):
                (folder / "stdout.txt").write_bytes(out)
                (folder / "stderr.txt").write_bytes(err)
        tail = _stderr_tail(err)
        where = f" (work folder {folder})" if folder is not None else ""
        if returncode != 0:
            code = returncode
            how = f"killed by signal {signal.Signals(-code).name}" if code < 0 and -code in signal.valid_signals() \
                else f"exit code {code}"
            raise SimulatorFailure(f"{how}; stderr: {tail or '(empty)'}{where}")
        context = f"; exit code 0; stderr: {tail or '(empty)'}{where}"
        if self.exchange == "files":
            try:
                text = (folder / "outputs.json").read_text()
            except OSError:
                raise SimulatorFailure(f"no outputs.json written{context}") from None
        else:
            text = out.decode("utf-8", "replace")
        try:
            parsed = _parse_object(text)
        except ValueError as exc:
            raise SimulatorFailure(f"unparsable output {exc}{context}") from None
        return checked_outputs(parsed, self.outputs, context)
