"""Fixtures that start real endpoints and always shut them down."""
import math
import re
import signal
import subprocess

import pytest

from opentmcl import VirtualModule
from opentmcl.server import PtyServer, Server, TcpServer

from ..capture.helpers import Tool
from .helpers import Link

GAP = 0.03  # short inter-byte gap so that resynchronisation tests stay quick


@pytest.fixture
def tcp_server():
    """A TMCM-6212 at address 1 served on an ephemeral loopback port."""
    server = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0, gap=GAP, max_clients=2, evict_silent=math.inf,
                               slot_wait=0.0))  # refused at once; tests/server/test_tcp_slots.py evicts
    server.start()
    try:
        yield server, tcp
    finally:
        server.stop()


class ServeProcess(Tool):
    """`python -m opentmcl serve ...` with its announced endpoints."""

    def __init__(self, *args):
        super().__init__("serve", *args)

    def tcp_address(self):
        m = re.match(r"tcp://([\d.]+):(\d+)", self.endpoint("tcp"))
        return m.group(1), int(m.group(2))

    def stop(self, sig=signal.SIGTERM):
        self.proc.send_signal(sig)
        try:
            out, err = self.proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            self.kill()
            raise
        return self.proc.returncode, out.decode(), err.decode()

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.communicate(timeout=20)


@pytest.fixture
def serve():
    started = []

    def start(*args):
        p = ServeProcess(*args)
        started.append(p)
        return p

    yield start
    for p in started:
        if p.proc.poll() is None:
            p.kill()
        else:
            p.proc.communicate(timeout=20)


@pytest.fixture
def pty_link():
    """`pty_link(name, **vm args)`: a module served alone on a pty (USB when its profile has USB),
    and a `Link` to it; both closed afterwards."""
    started = []

    def serve(name: str, **kw) -> Link:
        server = Server([VirtualModule(name, address=1, **kw)])
        pty = server.add(PtyServer(server.bus))
        server.start()
        started.append((server, Link(pty.path)))
        return started[-1][1]

    yield serve
    for server, lk in started:
        lk.close()
        server.stop()
