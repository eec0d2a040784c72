"""Real processes for the capture tests: `opentmcl serve` and `opentmcl proxy` as a user runs them."""
from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import time

from opentmcl.protocol.frame import Request


class Tool:
    """`python -m opentmcl ARGS...` that announces its endpoints and ends with "Press Ctrl-C"."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "opentmcl", *args], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE)
        self.lines: list[str] = []
        deadline = time.monotonic() + 30
        while not any(line.startswith("Press Ctrl-C") for line in self.lines):
            line = self._readline(deadline)
            if line is None:
                self.proc.kill()
                self.proc.wait()
                raise AssertionError(f"{args[0]} did not start: {self.lines} {self.proc.stderr.read()!r}")
            self.lines.append(line)

    def _readline(self, deadline: float) -> str | None:
        buf = b""
        while not buf.endswith(b"\n"):
            left = deadline - time.monotonic()
            ready, _, _ = select.select([self.proc.stdout], [], [], max(0.0, left))
            if left <= 0 or not ready:
                return None
            ch = os.read(self.proc.stdout.fileno(), 1)
            if not ch:
                return None
            buf += ch
        return buf.decode().strip()

    def endpoint(self, kind: str) -> str:
        for line in self.lines:
            if line.startswith(kind + " "):
                return line.split()[1]
        raise KeyError(kind)

    def stop(self) -> tuple[int, str, str]:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            out, err = self.proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, err = self.proc.communicate()
        return self.proc.returncode, out.decode(), err.decode()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


def cli(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], capture_output=True, text=True,
                          timeout=timeout)


def frame(command: int, type_: int = 0, motor: int = 0, value: int = 0, address: int = 1) -> bytes:
    return Request(address, command, type_, motor, value).encode()
