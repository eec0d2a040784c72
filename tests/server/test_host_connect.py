"""The host library's connect() against every served endpoint: tcp, serial (pty), can."""
import sys

import pytest

from opentmcl import VirtualModule
from opentmcl.host import connect
from opentmcl.server import CanServer, PtyServer, Server, TcpServer

from .helpers import unique_channel


@pytest.fixture
def server():
    channel = unique_channel()
    srv = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = srv.add(TcpServer(srv.bus, "127.0.0.1", 0))
    pty = srv.add(PtyServer(srv.bus)) if sys.platform != "win32" else None
    srv.add(CanServer(srv.bus, "virtual", channel))
    srv.start()
    urls = {"tcp": tcp.url, "can": f"can://virtual/{channel}?id=1"}
    if pty is not None:
        urls["serial"] = f"serial://{pty.path}?baud=9600"
    try:
        yield srv, urls
    finally:
        srv.stop()


@pytest.mark.parametrize("kind", ["tcp", "serial", "can"])
def test_connect_reads_version_and_moves(server, kind):
    """Command 136 type 0 (manual 3.6.36), GGP 66 (3.6.8) and an MVP with the 138 event
    (3.6.4, 3.6.35) through connect(url) on each endpoint, in real time."""
    srv, urls = server
    if kind not in urls:
        pytest.skip("pseudo-terminals need POSIX")
    m = connect(urls[kind])
    try:
        assert m.firmware_version() == srv.modules[0].profile.firmware_version
        assert m.get_global(66) == 1
        m.axes[0].set("max_positioning_speed", 20000)
        m.axes[0].move_to(1500, wait=True, timeout=10)
        assert m.axes[0].position == 1500
    finally:
        m.close()
