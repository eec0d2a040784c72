"""A program download belongs to the link that opened it (docs/endpoints.md "Several hosts").

TMCM-6212 manual 3.6.36, Table 13: 132 "enter download mode: All following commands (except
control commands) are not executed but stored in the TMCL memory"; 133 "exit download mode: End
the download mode. All following commands are executed normally again"; 134 "read program
memory". The manual knows one host per module; a served module has several links. The requests
of the links that did not open the download are executed as in direct mode and never stored; the
owner's are stored as the manual says. Found by tests/web/test_bench_served_and_on_a_link.py, where
the served dashboard's polling GAPs were stored into a program another host downloaded.

Every test runs real endpoints (an `opentmcl serve` process, or a `Server` with its TCP endpoint
and the served dashboard's `BusTransport`) over real sockets.
"""
from __future__ import annotations

import logging
import socket
import time

import can
import pytest

from opentmcl import VirtualModule
from opentmcl.host import Client
from opentmcl.protocol.frame import FRAME_LEN, Reply
from opentmcl.server import CanServer, Server, TcpServer
from opentmcl.server.bus import ModuleBus
from opentmcl.server.downloads import SILENT
from opentmcl.web.bus_transport import BusTransport

from .helpers import recv_exactly, request, unique_channel

OK, LOADED, NOT_AVAILABLE = 100, 101, 6
GAP, SAP, MST, ROR = 6, 5, 3, 1
ENTER, EXIT, READ = 132, 133, 134
EMPTY = (0, 0, 0, 0)
POSITION = -12345
# WAIT POS, GAP 1, MVP ABS: the instructions of the program whose read-back failed
PROGRAM = [(27, 1, 0, 0) if i % 3 == 0 else (6, 1, 0, 0) if i % 3 == 1 else (4, 0, 0, 1000 * i)
           for i in range(60)]


def ask(sock: socket.socket, command: int, type_: int = 0, motor: int = 0, value: int = 0) -> Reply:
    """One request to the module at address 1 and its 9-byte reply (manual 3.2)."""
    sock.sendall(request(1, command, type_, motor, value))
    raw = recv_exactly(sock, FRAME_LEN, timeout=30)
    assert len(raw) == FRAME_LEN, f"no reply to command {command}"
    return Reply.decode(raw)


def read_back(sock: socket.socket, count: int) -> list[tuple[int, int, int, int]]:
    """134 for addresses 0..count-1: the special reply carries command, type, motor, value."""
    out = []
    for address in range(count):
        sock.sendall(request(1, READ, 0, 0, address))
        raw = recv_exactly(sock, FRAME_LEN, timeout=30)
        out.append((raw[1], raw[2], raw[3], int.from_bytes(raw[4:8], "big", signed=True)))
    return out


def wait_for(condition, what: str, timeout: float = 30.0):
    """Poll `condition()` until it is true (bounded: a busy machine is slow, never wrong)."""
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        assert time.monotonic() < deadline, f"{what} within {timeout} s"
        time.sleep(0.02)


@pytest.fixture
def served():
    """A TMCM-6212 at address 1 on a `Server` with a TCP endpoint, as `opentmcl serve` builds it;
    `connect()` opens a TCP link."""
    server = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0, max_clients=4))
    server.start()
    socks: list[socket.socket] = []

    def connect() -> socket.socket:
        sock = socket.create_connection(tcp.address, timeout=30)
        socks.append(sock)
        return sock
    try:
        yield server, tcp, connect
    finally:
        for sock in socks:
            sock.close()
        server.stop()


def test_a_poll_from_another_serve_client_is_not_stored(serve):
    """The reproduction, on an `opentmcl serve` process: one TCP client downloads instruction by
    instruction (132 ... 133) while another sends GAP 1, 0 between every two of them. 3.6.36: the
    downloader's instructions "are not executed but stored" (status 101); the other client's GAPs
    are answered with the true actual position (status 100), and 134 reads back exactly the program
    downloaded, with nothing after it."""
    host, port = serve("--module", "TMCM-6212", "--tcp", "127.0.0.1:0").tcp_address()
    with socket.create_connection((host, port), timeout=30) as loader, \
            socket.create_connection((host, port), timeout=30) as poller:
        assert ask(poller, SAP, 1, 0, POSITION).status == OK  # AP1 actual position (4.1)
        assert ask(loader, ENTER, 0, 0, 0).status == OK
        stored, polled = [], []
        for ins in PROGRAM:
            stored.append(ask(loader, *ins).status)
            polled.append(ask(poller, GAP, 1, 0))
        assert ask(loader, EXIT).status == OK
        assert read_back(loader, len(PROGRAM) + 1) == [*PROGRAM, EMPTY]
    assert stored == [LOADED] * len(PROGRAM)
    assert [(r.status, r.value) for r in polled] == [(OK, POSITION)] * len(PROGRAM)


def test_the_served_dashboards_polls_are_not_stored(served):
    """The failing set-up itself: the served dashboard (its `BusTransport`, a link of its own)
    polls GAP 1, 0 between the instructions a TCP client downloads. 3.6.36: the program reads back
    as downloaded; the dashboard's GAPs get the true position (status 100)."""
    server, _tcp, connect = served
    loader = connect()
    dashboard = Client(BusTransport(server.bus), address=1, timeout=30)
    try:
        assert dashboard.request(SAP, 1, 0, POSITION).status == OK
        assert ask(loader, ENTER, 0, 0, 0).status == OK
        polled = []
        for ins in PROGRAM:
            assert ask(loader, *ins).status == LOADED
            reply = dashboard.request(GAP, 1, 0)
            polled.append((reply.status, reply.value))
        assert ask(loader, EXIT).status == OK
        assert read_back(loader, len(PROGRAM) + 1) == [*PROGRAM, EMPTY]
        assert polled == [(OK, POSITION)] * len(PROGRAM)
    finally:
        dashboard.close()


def test_the_served_dashboards_own_download_is_its_own(served):
    """The other way round: the served dashboard opens a download (3.6.36); a TCP client's GAP 1, 0
    between its instructions gets the true position and its 132 is refused (6). When the
    dashboard's link closes mid-download, the TCP client's 132 opens a download of its own."""
    server, _tcp, connect = served
    other = connect()
    assert ask(other, SAP, 1, 0, POSITION).status == OK
    dashboard = Client(BusTransport(server.bus), address=1, timeout=30)
    assert dashboard.request(ENTER, 0, 0, 0).status == OK
    polled = []
    for ins in PROGRAM[:6]:
        assert dashboard.request(*ins).status == LOADED
        reply = ask(other, GAP, 1, 0)
        polled.append((reply.status, reply.value))
    assert ask(other, ENTER, 0, 0, 20).status == NOT_AVAILABLE
    dashboard.close()
    assert ask(other, ENTER, 0, 0, 20).status == OK
    assert ask(other, MST, 0, 0).status == LOADED
    assert ask(other, EXIT).status == OK
    assert polled == [(OK, POSITION)] * 6
    assert read_back(other, 7) == [*PROGRAM[:6], EMPTY]
    assert read_back(other, 22)[20:] == [(MST, 0, 0, 0), EMPTY]


def test_a_stop_from_another_link_stops_the_motor_during_a_download(served):
    """Issue 28: a stop always gets through. During one client's download (3.6.36) another
    client's MST (3.6.3) is executed at once: the rotating motor's actual speed (GAP 3) reaches 0,
    and the MST is not in the program read back."""
    _server, _tcp, connect = served
    loader, other = connect(), connect()
    assert ask(other, ROR, 0, 0, 2000).status == OK
    wait_for(lambda: ask(other, GAP, 3, 0).value != 0, "the motor turns")
    assert ask(loader, ENTER, 0, 0, 0).status == OK
    assert ask(loader, *PROGRAM[0]).status == LOADED
    stop = ask(other, MST, 0, 0, 0)
    assert (stop.status, stop.command) == (OK, MST)
    wait_for(lambda: ask(other, GAP, 3, 0).value == 0, "the motor stands still")
    assert ask(loader, *PROGRAM[1]).status == LOADED
    assert ask(loader, EXIT).status == OK
    assert read_back(loader, 3) == [PROGRAM[0], PROGRAM[1], EMPTY]


def test_the_owner_closing_mid_download_lets_another_link_download(served):
    """While one client's download is open (3.6.36), another client's 132 is refused ("Command not
    available", 6: that download is not its own) and stores nothing. Once the owner has closed
    its connection, the other client's 132 opens its own download, its instructions are stored
    (101), and 134 reads its program back."""
    _server, _tcp, connect = served
    owner, other = connect(), connect()
    assert ask(owner, ENTER, 0, 0, 0).status == OK
    assert ask(owner, *PROGRAM[0]).status == LOADED
    refused = ask(other, ENTER, 0, 0, 10)
    assert (refused.status, refused.command) == (NOT_AVAILABLE, ENTER)
    assert ask(owner, *PROGRAM[1]).status == LOADED
    owner.close()
    wait_for(lambda: ask(other, ENTER, 0, 0, 10).status == OK, "the download is released")
    mine = [(5, 4, 0, 777), (3, 0, 0, 0), (6, 1, 0, 0)]  # SAP, MST, GAP: stored, not executed
    assert [ask(other, *ins).status for ins in mine] == [LOADED] * 3
    assert ask(other, EXIT).status == OK
    assert read_back(other, 2) == PROGRAM[:2]
    assert read_back(other, 14)[10:] == [*mine, EMPTY]
    assert ask(other, GAP, 4, 0).value != 777  # the SAP was stored, not executed


def test_a_can_host_is_another_link(served):
    """CAN is a link of its own (manual 3.1: the CAN ID is the address): during a TCP client's
    download (3.6.36) a CAN host's GAP 1, 0 is answered with the true position and its 132 is
    refused (6); the program reads back as the TCP client downloaded it."""
    server, _tcp, connect = served
    channel = unique_channel()
    server.add(CanServer(server.bus, "virtual", channel))
    host = can.Bus(interface="virtual", channel=channel)
    try:
        def over_can(command, type_=0, motor=0, value=0) -> tuple[int, int]:
            data = bytes((command, type_, motor)) + value.to_bytes(4, "big", signed=True)
            host.send(can.Message(arbitration_id=1, data=data, is_extended_id=False))
            msg = host.recv(30)
            assert msg is not None, f"no CAN reply to command {command}"
            return msg.data[1], int.from_bytes(msg.data[3:7], "big", signed=True)
        assert over_can(SAP, 1, 0, POSITION)[0] == OK
        loader = connect()
        assert ask(loader, ENTER, 0, 0, 0).status == OK
        polled = []
        for ins in PROGRAM[:6]:
            assert ask(loader, *ins).status == LOADED
            polled.append(over_can(GAP, 1, 0))
        assert over_can(ENTER, 0, 0, 0)[0] == NOT_AVAILABLE
        assert ask(loader, EXIT).status == OK
        assert read_back(loader, 7) == [*PROGRAM[:6], EMPTY]
        assert polled == [(OK, POSITION)] * 6
    finally:
        host.shutdown()


def test_a_lone_host_is_served_as_the_manual_says(served):
    """One host (the manual's set-up, unchanged): after its 132 every command but the control
    commands is stored (3.6.36), a GAP and an MST included; 133 ends it. A download left open by a
    closed connection stays open for the next connection (as a module whose host reconnects)."""
    server, _tcp, connect = served
    host = connect()
    assert ask(host, ENTER, 0, 0, 0).status == OK
    assert ask(host, GAP, 1, 0).status == LOADED
    host.close()
    end = time.monotonic() + 30  # the server notices the close in its own time (a busy machine)
    while server.bus.downloads.owners:
        assert time.monotonic() < end, "the closed connection still owns the download"
        time.sleep(0.01)
    again = connect()
    assert ask(again, MST, 0, 0).status == LOADED
    assert ask(again, 135, 0).status == OK  # a control command is executed
    assert ask(again, EXIT).status == OK
    assert read_back(again, 3) == [(GAP, 1, 0, 0), (MST, 0, 0, 0), EMPTY]
    assert ask(again, GAP, 1, 0).status == OK


class Link:
    """A link as the bus sees one (an endpoint's session): its identity, no events wanted."""

    interface = "serial"

    def deliver(self, vm, reply: bytes) -> None:
        pass


def test_a_silent_owner_loses_its_download_to_another_links_132(caplog):
    """3.6.36 download mode on a bus whose clock the test turns: another link's 132 is refused
    while the owner has been silent for less than `SILENT` seconds, and opens that link's own
    download once it has been silent that long (one log line); the former owner's requests are
    then direct-mode requests (executed, status 100)."""
    now = [0.0]
    vm = VirtualModule("TMCM-6212", address=1)
    bus = ModuleBus([vm], clock=lambda: now[0])
    owner, other = Link(), Link()

    def status(link, command, type_=0, motor=0, value=0):
        [(_vm, raw)] = bus.request(request(1, command, type_, motor, value), link)
        return raw[2]
    assert status(owner, ENTER) == OK
    now[0] += SILENT - 0.5
    assert status(other, ENTER) == NOT_AVAILABLE
    assert status(other, GAP, 1, 0) == OK
    now[0] += 0.5
    with caplog.at_level(logging.WARNING, logger="opentmcl.server"):
        assert status(other, ENTER, 0, 0, 5) == OK
    assert len([r for r in caplog.records if "silent" in r.getMessage()]) == 1
    assert status(other, SAP, 4, 0, 1234) == LOADED
    assert status(owner, SAP, 4, 0, 999) == OK
    assert status(other, EXIT) == OK
    assert vm.program.code[5:7] == [(SAP, 4, 0, 1234), EMPTY]
    assert vm.request(GAP, 4, 0).value == 999
