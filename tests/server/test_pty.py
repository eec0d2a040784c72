"""pty endpoint: the bus appears as a serial port that pyserial opens."""
import os
import sys
import time

import pytest
import serial

from opentmcl import VirtualModule
from opentmcl.host.errors import TmclConnectionError, TmclTimeout
from opentmcl.host.transports.serial import SerialTransport, open_serial
from opentmcl.server import PtyServer, Server

from .conftest import GAP
from .helpers import GGP_66, reply, request, wait_handled

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")


@pytest.fixture
def pty_server(tmp_path):
    server = Server([VirtualModule("TMCM-6212", address=1), VirtualModule("TMCM-6212", address=2)])
    pty = server.add(PtyServer(server.bus, link=tmp_path / "tmcm", gap=GAP))
    server.start()
    try:
        yield server, pty
    finally:
        server.stop()


def test_pyserial_talks_to_the_pty(pty_server):
    """Manual 3.6.8 GGP 66, 0 example through a real pseudo-terminal opened by pyserial."""
    _, pty = pty_server
    assert os.path.exists(pty.path)
    with serial.Serial(pty.path, 9600, timeout=5) as port:
        port.write(GGP_66)
        assert port.read(9) == reply(2, 1, 100, 10, 1)
        port.write(request(2, 10, 66, 0))  # the second module on the same bus
        assert port.read(9) == reply(2, 2, 100, 10, 2)


def test_symlink_points_at_the_pty_and_goes_away(tmp_path):
    """--link PATH: a stable name for the port, removed at shutdown."""
    server = Server([VirtualModule("TMCM-6212", address=1)])
    pty = server.add(PtyServer(server.bus, link=tmp_path / "port", gap=GAP))
    server.start()
    try:
        assert os.readlink(tmp_path / "port") == pty.path
        with serial.Serial(str(tmp_path / "port"), timeout=5) as port:
            port.write(GGP_66)
            assert port.read(9) == reply(2, 1, 100, 10, 1)
    finally:
        server.stop()
    assert not os.path.lexists(tmp_path / "port")


def test_link_never_replaces_a_regular_file(tmp_path):
    target = tmp_path / "precious"
    target.write_text("keep me")
    server = Server([VirtualModule("TMCM-6212", address=1)])
    server.add(PtyServer(server.bus, link=target))
    with pytest.raises(FileExistsError):
        server.start()
    server.stop()
    assert target.read_text() == "keep me"


def test_reopening_the_port_works(pty_server):
    """Clients may open and close the port repeatedly (the server holds the slave open)."""
    _, pty = pty_server
    for _ in range(3):
        with serial.Serial(pty.path, timeout=5) as port:
            port.write(GGP_66)
            assert port.read(9) == reply(2, 1, 100, 10, 1)


def test_truncated_frame_resynchronises_on_the_pty(pty_server):
    """A truncated command followed by a pause never wedges the port."""
    _, pty = pty_server
    with serial.Serial(pty.path, timeout=5) as port:
        port.write(GGP_66[:4])
        port.flush()
        wait_handled(pty.session, 4)
        time.sleep(GAP * 3)
        port.write(GGP_66)
        assert port.read(9) == reply(2, 1, 100, 10, 1)


def test_serial_transport_over_pty(pty_server):
    """Host transport serial:///dev/pts/N?baud=9600 (9600 = GP65 default, manual 5.1)."""
    import urllib.parse

    _, pty = pty_server
    t = open_serial(urllib.parse.urlsplit(f"serial://{pty.path}?baud=9600"))
    try:
        t.send(GGP_66)
        assert t.recv(9, 5) == reply(2, 1, 100, 10, 1)
        t.send(request(7, 10, 66, 0))
        with pytest.raises(TmclTimeout):
            t.recv(9, 0.2)
    finally:
        t.close()
        t.close()


def test_serial_transport_errors(tmp_path):
    import urllib.parse

    with pytest.raises(TmclConnectionError):
        SerialTransport(str(tmp_path / "no-such-port"))
    for url in ("serial://", "serial:///dev/x?baud=fast", "serial:///dev/x?baud=0"):
        with pytest.raises(TmclConnectionError):
            open_serial(urllib.parse.urlsplit(url))


def test_a_client_that_never_reads_cannot_wedge_the_server(pty_server):
    """Replies nobody reads fill the terminal buffer and are then dropped; the server keeps
    answering (safety, docs/endpoints.md). Manual 3.6.8 GGP 66 example as the probe."""
    import termios

    _, pty = pty_server
    fd = os.open(pty.path, os.O_RDWR | os.O_NOCTTY)
    try:
        import tty

        tty.setraw(fd)
        burst = GGP_66 * 100
        deadline = time.monotonic() + 60
        while pty.dropped == 0 and time.monotonic() < deadline:  # replies are never read
            os.write(fd, burst)
            time.sleep(0.01)
        assert pty.dropped > 0
        last = -1
        while pty.dropped != last and time.monotonic() < deadline:  # until the backlog is done
            last = pty.dropped
            time.sleep(0.3)
        termios.tcflush(fd, termios.TCIFLUSH)
    finally:
        os.close(fd)
    with serial.Serial(pty.path, timeout=0.3) as port:
        while port.read(4096):  # a loaded machine may still be answering the backlog (or part of it)
            pass
        port.timeout = 5
        port.write(GGP_66)
        assert port.read(9) == reply(2, 1, 100, 10, 1)


WIRE_9600 = 18 * 10 / 9600
"""A request and its reply, nine bytes each, ten bit times per byte (8N1) at 9600 baud (GP65 = 0)."""


def _round_trips(port, frame, expected, count):
    """Seconds each of `count` request/reply round trips took (lower bounds are all a test uses)."""
    times = []
    for _ in range(count):
        start = time.monotonic()
        port.write(frame)
        assert port.read(9) == expected
        times.append(time.monotonic() - start)
    return times


def test_paced_pty_round_trip_takes_the_wire_time_of_both_directions():
    """TMCM-6212 manual 5.1 GP65 "RS485 baud rate" 0 = 9600: with pacing a request reaches the
    module only once its ninth byte crossed the line, and the reply takes its wire time too, so
    every round trip takes at least 18 byte times (18.75 ms); only a lower bound is checked."""
    server = Server([VirtualModule("TMCM-6212", address=1)])
    pty = server.add(PtyServer(server.bus, gap=GAP, pace_bytes=True))
    server.start()
    try:
        with serial.Serial(pty.path, 9600, timeout=5) as port:
            times = _round_trips(port, GGP_66, reply(2, 1, 100, 10, 1), 10)
    finally:
        server.stop()
    assert min(times) >= WIRE_9600


def test_paced_rs485_bus_turn_around_adds_gp75():
    """Manual 5.1 GP75 "Pause time before the reply via RS485 is sent" (ms): on a paced RS-485
    bus of two modules a round trip to module 2 with GP75 = 20 takes at least 18 byte times
    + 20 ms."""
    server = Server([VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2)])
    pty = server.add(PtyServer(server.bus, gap=GAP, pace_bytes=True))
    server.start()
    try:
        with serial.Serial(pty.path, 9600, timeout=5) as port:
            port.write(request(2, 9, 75, 0, 20))          # SGP 75, 0, 20
            assert len(port.read(9)) == 9
            times = _round_trips(port, request(2, 10, 66, 0), reply(2, 2, 100, 10, 2), 5)
    finally:
        server.stop()
    assert min(times) >= WIRE_9600 + 0.020


def test_a_paced_pty_stands_for_an_rs485_line():
    """Manual 5.1 GP65 "RS485 baud rate": a paced pty is a line at that rate, so with one module it
    defaults to rs485 (address filtering, GP75) instead of usb, and usb with pacing is refused."""
    server = Server([VirtualModule("TMCM-6212", address=1)])
    assert PtyServer(server.bus).interface == "usb"
    assert PtyServer(server.bus, pace_bytes=True).interface == "rs485"
    with pytest.raises(ValueError, match="baud rate"):
        PtyServer(server.bus, pace_bytes=True, interface="usb")
