"""The transport contract (host/transport.py): `recv(n, timeout)` returns exactly n bytes or raises
TmclTimeout, and bytes that arrived before a timeout stay buffered for the next call — the client
listens for event replies (TMCM-6212 manual 3.6.35) in short slices, and a frame may straddle two."""
from __future__ import annotations

import os
import socket
import sys
import urllib.parse

import pytest

from opentmcl.host import TmclTimeout
from opentmcl.protocol.frame import Reply

FRAME = Reply(2, 1, 128, 138, 1).encode()  # the additional reply of command 138


def _check_split_frame(transport, write):
    write(FRAME[:4])
    with pytest.raises(TmclTimeout):
        transport.recv(9, 0.05)
    write(FRAME[4:])
    assert transport.recv(9, 2.0) == FRAME


def test_tcp_keeps_bytes_received_before_a_timeout():
    from opentmcl.host.transports.tcp import open_tcp

    listener = socket.create_server(("127.0.0.1", 0))
    port = listener.getsockname()[1]
    t = open_tcp(urllib.parse.urlsplit(f"tcp://127.0.0.1:{port}"))
    peer, _ = listener.accept()
    try:
        _check_split_frame(t, peer.sendall)
    finally:
        t.close()
        peer.close()
        listener.close()


@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")
def test_serial_keeps_bytes_received_before_a_timeout():
    from opentmcl.host.transports.serial import open_serial

    master, slave = os.openpty()
    t = open_serial(urllib.parse.urlsplit(f"serial://{os.ttyname(slave)}?baud=9600"))
    try:
        _check_split_frame(t, lambda b: os.write(master, b))
    finally:
        t.close()
        os.close(master)
        os.close(slave)
