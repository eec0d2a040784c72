"""Pipelining on the TCP and pty endpoints: several frames that arrive in one read are answered in
order, at once, and their replies written together.

TMCM-6212 manual 3.1 (nine-byte request, checksum 3.1.1), 3.2 (reply format; status 1 "wrong
checksum" in 3.2.1), 3.6.8 (GGP example 01 0A 42 00 00 00 00 00 4D).
"""
from __future__ import annotations

import socket
import sys
import urllib.parse

import pytest
import serial

import opentmcl
from opentmcl import VirtualModule
from opentmcl.host import Client, Module
from opentmcl.host.transports.serial import open_serial
from opentmcl.server import PtyServer, Server, TcpServer
from opentmcl.server.bus import ModuleBus
from opentmcl.server.session import SerialSession

from .helpers import GGP_66, only_session, recv_exactly, reply, request, wait_handled

SLOW_GAP = 5.0  # a frame split across reads must not expire on a loaded machine
SGP_V0 = request(1, 9, 0, 2, 11)   # SGP 0, 2, 11: user variable 0
GGP_V0 = request(1, 10, 0, 2)      # GGP 0, 2
GGP_V0_BAD = GGP_V0[:8] + bytes(((GGP_V0[8] + 1) & 0xFF,))


def bad_checksum_reply() -> bytes:
    return reply(2, 1, 1, 10, 0)   # status 1: wrong checksum (manual 3.2.1)


def expected_three() -> bytes:
    return reply(2, 1, 100, 9, 0) + reply(2, 1, 100, 10, 1) + reply(2, 1, 100, 10, 11)


@pytest.fixture
def tcp():
    server = Server([VirtualModule("TMCM-6212", address=1)])
    endpoint = server.add(TcpServer(server.bus, "127.0.0.1", 0, gap=SLOW_GAP))
    server.start()
    try:
        yield endpoint
    finally:
        server.stop()


@pytest.fixture
def pty():
    if sys.platform == "win32":
        pytest.skip("pseudo-terminals need POSIX")
    server = Server([VirtualModule("TMCM-6212", address=1)])
    endpoint = server.add(PtyServer(server.bus, gap=SLOW_GAP, interface="rs485"))
    server.start()
    try:
        yield endpoint
    finally:
        server.stop()


def test_three_frames_in_one_write_over_tcp(tcp):
    """SGP, the manual's GGP 66 example and a GGP in one write: three replies, in order, with
    nothing more sent."""
    with socket.create_connection(tcp.address, timeout=5) as s:
        s.sendall(SGP_V0 + GGP_66 + GGP_V0)
        assert recv_exactly(s, 27) == expected_three()


def test_frame_split_across_reads_over_tcp(tcp):
    """One frame and four bytes, then the rest: the first reply comes before the rest is sent."""
    data = SGP_V0 + GGP_66 + GGP_V0
    with socket.create_connection(tcp.address, timeout=5) as s:
        s.sendall(data[:13])
        assert recv_exactly(s, 9) == expected_three()[:9]
        wait_handled(only_session(tcp), 13)
        s.sendall(data[13:])
        assert recv_exactly(s, 18) == expected_three()[9:]


def test_bad_checksum_in_the_middle_over_tcp(tcp):
    """A wrong checksum in the second of three frames: status 1 for it, the others as usual, and
    the stream stays in step (the frame is nine bytes still)."""
    with socket.create_connection(tcp.address, timeout=5) as s:
        s.sendall(SGP_V0 + GGP_V0_BAD + GGP_V0)
        assert recv_exactly(s, 27) == reply(2, 1, 100, 9, 0) + bad_checksum_reply() + reply(2, 1, 100, 10, 11)


def test_request_many_over_tcp_has_frames_in_flight(tcp):
    """The client sends a window of eight, the server answers each in order."""
    m = opentmcl.connect(tcp.url, profile="TMCM-6212")
    try:
        answers = m.request_many([(9, i, 2, 100 + i) for i in range(16)] + [(10, i, 2, 0) for i in range(16)])
        assert [a.value for a in answers[16:]] == [100 + i for i in range(16)]
    finally:
        m.close()


def test_three_frames_in_one_write_over_a_pty(pty):
    with serial.Serial(pty.path, 9600, timeout=5) as port:
        port.write(SGP_V0 + GGP_66 + GGP_V0)
        assert port.read(27) == expected_three()


def test_frame_split_and_bad_checksum_over_a_pty(pty):
    with serial.Serial(pty.path, 9600, timeout=5) as port:
        data = SGP_V0 + GGP_V0_BAD + GGP_V0
        port.write(data[:13])
        assert port.read(9) == reply(2, 1, 100, 9, 0)
        wait_handled(pty.session, 13)
        port.write(data[13:])
        assert port.read(18) == bad_checksum_reply() + reply(2, 1, 100, 10, 11)


def test_request_many_over_a_pty_with_a_window(pty):
    """``serial://PATH?window=8`` (the default is 1: docs/assumptions.md)."""
    t = open_serial(urllib.parse.urlsplit(f"serial://{pty.path}?window=8"))
    assert t.window == 8
    m = Module(Client(t), 1, "TMCM-6212")
    try:
        answers = m.request_many([(9, 5, 2, -5), (10, 5, 2, 0), (136, 0, 0, 0), (10, 66, 0, 0)])
        assert answers[1].value == -5 and answers[2].text == "6212V105" and answers[3].value == 1
    finally:
        m.close()
    loop = open_serial(urllib.parse.urlsplit("serial://?port=loop://"))
    assert loop.window == 1
    loop.close()


class Writes:
    def __init__(self):
        self.calls: list[bytes] = []

    def __call__(self, data: bytes) -> None:
        self.calls.append(bytes(data))


def test_replies_of_one_read_are_written_together():
    """The session writes the three replies of one read in one write (no telegram pause, GP75 = 0)."""
    writes = Writes()
    session = SerialSession(ModuleBus([VirtualModule("TMCM-6212", address=1)], clock=lambda: 0.0), writes)
    assert session.receive(SGP_V0 + GGP_66 + GGP_V0, now=0.0) == 3
    assert writes.calls == [expected_three()]


def test_a_telegram_pause_keeps_its_reply_apart():
    """GP75 = 5 ms on module 2 (manual 5.1 "pause time before the reply via RS485 is sent"): its
    reply is written on its own after the pause; the others still go out together, in order."""
    writes = Writes()
    slept: list[float] = []
    a, b = VirtualModule("TMCM-6212", address=1), VirtualModule("TMCM-6212", address=2)
    session = SerialSession(ModuleBus([a, b], clock=lambda: 0.0), writes, sleep=slept.append)
    session.receive(request(2, 9, 75, 0, 5), now=0.0)
    writes.calls.clear()
    slept.clear()
    session.receive(GGP_66 + GGP_V0 + request(2, 10, 66) + GGP_66, now=0.0)
    assert writes.calls == [reply(2, 1, 100, 10, 1) + reply(2, 1, 100, 10, 0), reply(2, 2, 100, 10, 2),
                            reply(2, 1, 100, 10, 1)]
    assert slept == [0.005]


def test_a_139_in_the_middle_switches_the_rest_to_ascii():
    """PD28-1021 manual 3.4.1: after command 139 the rest of the same read is ASCII text."""
    writes = Writes()
    vm = VirtualModule("PD28-1021", address=1)
    session = SerialSession(ModuleBus([vm], clock=lambda: 0.0), writes)
    session.receive(request(1, 139) + GGP_66, now=0.0)
    assert writes.calls[0] == reply(2, 1, 100, 139, 0)
    assert vm.ascii_mode is True
    assert reply(2, 1, 100, 10, 1) not in b"".join(writes.calls)
