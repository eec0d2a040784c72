"""Servers a benchmark starts in their own process, as a user runs them.

A server process prints one line per endpoint ("tcp tcp://HOST:PORT", "pty /dev/pts/N ...") and
then "Press Ctrl-C to stop." (`opentmcl serve` and `opentmcl proxy` do; so do the echo servers of
bench_endpoints.py); SIGTERM stops it.
"""
from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import time

READY = b"Press Ctrl-C"


def start(argv: list[str]) -> tuple[subprocess.Popen, list[str]]:
    """Start `argv`; wait until it announced its endpoints; return the process and its lines."""
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE)
    assert proc.stdout is not None
    deadline = time.monotonic() + 30
    buf = b""
    while READY not in buf:
        ready, _, _ = select.select([proc.stdout], [], [], max(0.0, deadline - time.monotonic()))
        ch = os.read(proc.stdout.fileno(), 1) if ready else b""
        if not ch:
            proc.kill()
            proc.wait()
            raise RuntimeError(f"{' '.join(argv[:4])} did not start: {buf!r}")
        buf += ch
    return proc, buf.decode().splitlines()


def start_tool(*args: str) -> tuple[subprocess.Popen, list[str]]:
    """`python -m opentmcl ARGS...` (serve, proxy)."""
    return start([sys.executable, "-m", "opentmcl", *args])


def endpoint(lines: list[str], kind: str) -> str:
    """The address a server printed for an endpoint kind ("tcp", "pty")."""
    for line in lines:
        words = line.split()
        if len(words) >= 2 and words[0] == kind:
            return words[1]
    raise RuntimeError(f"no {kind} endpoint in {lines!r}")


def stop(proc: subprocess.Popen) -> None:
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
    if proc.stdout is not None:
        proc.stdout.close()
