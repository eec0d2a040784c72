"""What the host library offers a program that takes a link over from the client (the capture
proxy, docs/capture.md "`opentmcl proxy`": "Host bytes go to the module ... as they arrive and
module bytes go back to every connected host as they arrive: nothing is framed"), documented in
docs/host.md "Writing a transport":

- `StreamTransport.read_some(timeout)`: the bytes a serial or TCP link delivers within `timeout`,
  unframed (b"" when nothing came), TmclConnectionError when the link broke or is closed;
- `CanTransport.bus`: the python-can bus under a CAN transport;
- `split_url(url)`: a module URL split as `open_transport` reads it.
"""
from __future__ import annotations

import os
import socket
import sys
import time
import urllib.parse

import pytest

from opentmcl.host import TmclConnectionError
from opentmcl.host.errors import TmclUrlError
from opentmcl.protocol.frame import Reply

FRAME = Reply(2, 1, 100, 6, 51200).encode()   # GAP reply, TMCM-6212 manual 3.2


def _read_until(transport, n: int, seconds: float = 20.0) -> bytes:
    """Bytes from `read_some` until `n` have come (a stream may cut them anywhere)."""
    got = b""
    deadline = time.monotonic() + seconds
    while len(got) < n and time.monotonic() < deadline:
        got += transport.read_some(0.2)
    return got


def _check_read_some(transport, write) -> None:
    write(FRAME[:4])   # part of a frame: read_some does not wait for the rest
    assert _read_until(transport, 4) == FRAME[:4]
    assert transport.read_some(0.05) == b""   # nothing more came
    write(FRAME[4:])
    assert _read_until(transport, 5) == FRAME[4:]
    transport.close()
    with pytest.raises(TmclConnectionError, match="closed"):
        transport.read_some(0.05)


@pytest.fixture
def tcp_pair():
    from opentmcl.host.transports.tcp import open_tcp

    listener = socket.create_server(("127.0.0.1", 0))
    port = listener.getsockname()[1]
    transport = open_tcp(urllib.parse.urlsplit(f"tcp://127.0.0.1:{port}"))
    peer, _ = listener.accept()
    yield transport, peer
    transport.close()
    peer.close()
    listener.close()


def test_tcp_read_some_returns_what_arrived(tcp_pair):
    transport, peer = tcp_pair
    _check_read_some(transport, peer.sendall)


def test_tcp_read_some_says_when_the_other_end_closed(tcp_pair):
    transport, peer = tcp_pair
    peer.close()
    with pytest.raises(TmclConnectionError, match="connection closed"):
        _read_until(transport, 1)


@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")
def test_serial_read_some_returns_what_arrived():
    from opentmcl.host.transports.serial import open_serial

    master, slave = os.openpty()
    transport = open_serial(urllib.parse.urlsplit(f"serial://{os.ttyname(slave)}?baud=9600"))
    try:
        _check_read_some(transport, lambda b: os.write(master, b))
    finally:
        transport.close()
        os.close(master)
        os.close(slave)


def test_can_transport_shows_its_bus():
    """The frames on the reply ID reach whoever reads `bus` (python-can's virtual interface)."""
    import can

    from opentmcl.host.transports.can import open_can

    channel = f"opentmcl-takeover-{os.getpid()}"
    transport = open_can(urllib.parse.urlsplit(f"can://virtual/{channel}?id=1&reply_id=2"))
    module = can.Bus(interface="virtual", channel=channel)
    try:
        assert isinstance(transport.bus, can.BusABC)
        module.send(can.Message(arbitration_id=2, data=FRAME[1:8], is_extended_id=False))
        msg = transport.bus.recv(20.0)
        assert msg is not None and msg.arbitration_id == 2 and bytes(msg.data) == FRAME[1:8]
    finally:
        module.shutdown()
        transport.close()


def test_split_url_reads_a_url_as_open_transport_does():
    """docs/host.md "Connecting": the scheme names the transport (any case); one sim:// module
    takes the address the caller talks to unless the URL sets one."""
    from opentmcl.host.connect import split_url

    assert split_url("TCP://127.0.0.1:2323") == urllib.parse.urlsplit("tcp://127.0.0.1:2323")
    assert split_url("sim://TMCM-6212").query == ""
    assert split_url("sim://TMCM-6212", 3).query == "address=3"
    assert split_url("sim://TMCM-6212@5", 3).query == ""   # the URL's own address stays
    with pytest.raises(TmclUrlError, match="not a module URL"):
        split_url("/dev/ttyUSB0")
