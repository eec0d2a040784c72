"""Served modules as real processes for the issue-28 tests: `opentmcl serve --web`, or `opentmcl
serve` with `opentmcl dashboard --to URL` in front of it (over TCP, or over a pty paced at 9600
baud), and the test's own TCP client of the module, which watches it over a second connection."""
from __future__ import annotations

import subprocess
import sys
import time
import urllib.parse
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from .rawhttp import start_cli, stop_cli

GENEROUS = 30.0  # seconds: a guard against hanging, never a timing assert


@dataclass
class Served:
    port: int           # the dashboard's
    tcp: str            # tcp://HOST:PORT of the module


def _serve(*extra: str) -> tuple[subprocess.Popen, dict[str, str]]:
    """`opentmcl serve --module TMCM-6212 --tcp 127.0.0.1:0 EXTRA`: the process and its endpoints
    as printed ("tcp", "pty": a serial:// URL)."""
    proc = subprocess.Popen([sys.executable, "-m", "opentmcl", "serve", "--module", "TMCM-6212", "--tcp",
                             "127.0.0.1:0", *extra], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    ends: dict[str, str] = {}
    assert proc.stdout is not None
    for line in proc.stdout:
        words = line.split()
        if words[:1] == ["tcp"]:
            ends["tcp"] = words[-1]
        if words[:1] == ["pty"]:
            ends["pty"] = next(w for w in words if w.startswith("serial://"))
        if line.startswith("Press Ctrl-C"):
            return proc, ends
    proc.wait()
    raise AssertionError("opentmcl serve did not start")


@contextmanager
def served_module(mode: str) -> Iterator[Served]:
    """"serve": `opentmcl serve --web`; "dashboard": `opentmcl dashboard --to tcp://...` in front of
    `opentmcl serve`; "paced": `opentmcl dashboard --to serial://PTY?baud=9600` in front of
    `opentmcl serve --pty --pace` (its bytes paced at GP65's 9600 baud, TMCM-6212 manual 5.1)."""
    if mode == "serve":
        proc, url, lines = start_cli(["serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0",
                                      "--web", "127.0.0.1:0"], "dashboard http")
        tcp = next(line.split()[-1] for line in lines if line.strip().startswith("tcp "))
        try:
            yield Served(urllib.parse.urlsplit(url).port or 0, tcp)
        finally:
            out = stop_cli(proc)
            assert "Traceback" not in out, out
        return
    module, ends = _serve(*(["--pty", "--pace"] if mode == "paced" else []))
    try:
        to = f"{ends['pty']}?baud=9600" if mode == "paced" else ends["tcp"]
        proc, url, _ = start_cli(["dashboard", "--to", to, "--web", "127.0.0.1:0"], "dashboard for")
        try:
            yield Served(urllib.parse.urlsplit(url).port or 0, ends["tcp"])
        finally:
            out = stop_cli(proc)
            assert "Traceback" not in out, out
    finally:
        stop_cli(module)


@contextmanager
def watcher(served: Served):
    """The test's own TCP client of the module (a second connection, not the dashboard's)."""
    from opentmcl.host import Client
    from opentmcl.host.transports.tcp import TcpTransport

    host, port = served.tcp.removeprefix("tcp://").rsplit(":", 1)
    client = Client(TcpTransport(host, int(port)), timeout=10.0)
    try:
        yield client
    finally:
        client.close()


def wait_for(predicate, what: str) -> None:
    """Poll `predicate` until true; fail naming `what` after GENEROUS seconds."""
    end = time.monotonic() + GENEROUS
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"not reached: {what}")
        time.sleep(0.02)
