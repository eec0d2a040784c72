"""Trigger a named fault while serving (`opentmcl serve --faults FILE --fault-control PATH`,
`opentmcl fault NAME --control PATH`; docs/faults.md "Triggering by name").

A Unix socket at PATH, readable and writable by its owner only (mode 0600), takes one command line
per connection and answers one JSON line:

    trigger NAME    -> {"ok": true, "fired": ["..."]}   or {"ok": false, "error": "..."}
    list            -> {"ok": true, "names": [...], "seed": N, "fired": ["<time> s  <fault>: <what>", ...]}

A command line is at most `MAX_LINE` bytes and must arrive within `TIMEOUT` seconds; the socket
only ever triggers faults the served plan names (nothing else can be done through it).
"""
from __future__ import annotations

import contextlib
import json
import os
import socket
import stat
import threading
from pathlib import Path

from ..faults import FaultBoard, FaultError

MAX_LINE = 256
TIMEOUT = 2.0
FIRED_SHOWN = 50
"""The most recent records `list` answers."""


def answer(board: FaultBoard, line: str) -> dict:
    """The answer to one command line."""
    command, _, arg = line.strip().partition(" ")
    if command == "trigger" and arg.strip():
        try:
            return {"ok": True, "fired": board.trigger(arg.strip())}
        except FaultError as exc:
            return {"ok": False, "error": str(exc)}
    if command == "list" and not arg:
        fired = board.log.since(max(0, len(board.log) - FIRED_SHOWN))
        return {"ok": True, "names": board.names(), "seed": board.seed, "fired": [f.text() for f in fired]}
    return {"ok": False, "error": "commands: 'trigger NAME' or 'list'"}


class FaultControl:
    """The control socket of a served fault plan; `start()` binds, `stop()` removes it."""

    def __init__(self, board: FaultBoard, path: str | os.PathLike[str]) -> None:
        self.board = board
        self.path = Path(path)
        self._sock: socket.socket | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        if self.path.exists() or self.path.is_symlink():
            if not stat.S_ISSOCK(self.path.lstat().st_mode):
                raise FileExistsError(f"{self.path} exists and is not a socket; not replacing it")
            self.path.unlink()
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        old = os.umask(0o177)  # the owner only, from the moment it exists
        try:
            sock.bind(str(self.path))
        except OSError:
            sock.close()
            raise
        finally:
            os.umask(old)
        sock.listen(4)
        sock.settimeout(0.2)
        self._sock = sock
        self._thread = threading.Thread(target=self._loop, name="opentmcl-fault-control", daemon=True)
        self._thread.start()

    def _loop(self) -> None:
        while not self._stop.is_set():
            sock = self._sock
            if sock is None:
                return
            try:
                conn, _ = sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            with conn:
                self._serve(conn)

    def _serve(self, conn: socket.socket) -> None:
        conn.settimeout(TIMEOUT)
        data = b""
        with contextlib.suppress(OSError):
            while b"\n" not in data and len(data) <= MAX_LINE:
                chunk = conn.recv(MAX_LINE + 1 - len(data))
                if not chunk:
                    break
                data += chunk
        if len(data) > MAX_LINE:
            out = {"ok": False, "error": f"a command line is at most {MAX_LINE} bytes"}
        else:
            out = answer(self.board, data.decode("utf-8", "replace"))
        with contextlib.suppress(OSError):
            conn.sendall((json.dumps(out) + "\n").encode())

    def stop(self) -> None:
        self._stop.set()
        if self._sock is not None:
            self._sock.close()
            self._sock = None
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        with contextlib.suppress(OSError):
            if stat.S_ISSOCK(self.path.lstat().st_mode):
                self.path.unlink()


def ask(path: str | os.PathLike[str], line: str, timeout: float = 5.0) -> dict:
    """Send one command line to the control socket at `path`; its answer. OSError if unreachable."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
        sock.settimeout(timeout)
        sock.connect(os.fspath(path))
        sock.sendall(line.encode() + b"\n")
        data = b""
        while not data.endswith(b"\n"):
            chunk = sock.recv(65536)
            if not chunk:
                break
            data += chunk
            if len(data) > 4 * 1024 * 1024:
                raise OSError("answer too long")
    try:
        out = json.loads(data)
    except ValueError:
        raise OSError(f"not an answer of opentmcl serve: {data[:80]!r}") from None
    if not isinstance(out, dict):
        raise OSError("not an answer of opentmcl serve")
    return out
