"""Fixtures that start real endpoints and always shut them down."""
import pytest

from opentmcl import VirtualModule
from opentmcl.server import Server, TcpServer

GAP = 0.03  # short inter-byte gap so that resynchronisation tests stay quick


@pytest.fixture
def tcp_server():
    """A TMCM-6212 at address 1 served on an ephemeral loopback port."""
    server = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0, gap=GAP, max_clients=2))
    server.start()
    try:
        yield server, tcp
    finally:
        server.stop()
