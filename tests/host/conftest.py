"""Fixtures of the host tests."""

import pytest

from opentmcl import VirtualModule
from opentmcl.server import Server, TcpServer


@pytest.fixture
def tcp_url():
    """A TMCM-6212 at address 1 served on a real loopback TCP port; its ``tcp://`` URL."""
    srv = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = srv.add(TcpServer(srv.bus, "127.0.0.1", 0))
    srv.start()
    try:
        yield tcp.url
    finally:
        srv.stop()
