"""ASCII mode over the serial endpoints (PD28-1021 manual 3.4, PD86-1180 manual 4.5).

Entered with binary command 139 or at start-up with GP67 bit 0, left with BIN; echo per
GP67 bits 4/5; backspace editing; replies like ``BA 100 -5000``. The byte stream of a
session, the pty and TCP endpoints and the ``opentmcl://`` port route text to the modules
in ASCII mode and go back to binary framing after BIN.
"""
import socket
import sys
import time

import pytest
import serial

import opentmcl.urlhandler  # noqa: F401
from opentmcl import VirtualModule
from opentmcl.server import PtyServer, Server, TcpServer
from opentmcl.server.bus import ModuleBus
from opentmcl.server.session import SerialSession

from .conftest import GAP
from .helpers import GGP_66, is_ok, recv_exactly, reply, request

ENTER_ASCII = request(1, 139)  # binary command 139 "enter ASCII mode" to module 1
ENTERED = reply(2, 1, 100, 139, 0)
posix_only = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")


class Link:
    """A session on a bus with a hand-driven clock; collects what the modules write."""

    def __init__(self, *modules):
        self.t = 0.0
        self.bus = ModuleBus(modules, clock=lambda: self.t)
        self.written = bytearray()
        self.session = SerialSession(self.bus, self.written.extend, gap=GAP, clock=lambda: self.t,
                                     sleep=lambda s: None)

    def send(self, data: bytes) -> bytes:
        self.written.clear()
        self.session.receive(data)
        return bytes(self.written)

    def pause(self):
        self.t += 10 * GAP


# --- the byte stream of one session ------------------------------------------------------

@pytest.mark.parametrize("name", ["PD28-1021", "PD86-1180"])
def test_139_switches_the_rest_of_the_stream_to_ascii(name):
    """3.4.1: "The ASCII command line interface is entered by sending the binary command 139";
    3.4.4: with GP67 = 0 "every character that is entered will be echoed back"; 3.4.3 reply
    format (host address character B, module address character A, status, value, <CR>)."""
    link = Link(VirtualModule(name, address=1))
    out = link.send(ENTER_ASCII + b"AGGP 66, 0\r")
    assert out == ENTERED + b"AGGP 66, 0" + b"\r" + b"BA 100 1\r"


def test_bin_line_hands_the_following_bytes_back_to_binary_framing():
    """3.4.1: "For leaving the ASCII mode and re-entering the binary mode enter the command BIN";
    the manual's GGP 66, 0 frame (TMCM-6212 manual 3.6.8) right after it is a binary request."""
    link = Link(VirtualModule("PD28-1021", address=1))
    link.send(ENTER_ASCII)
    out = link.send(b"ABIN\r" + GGP_66 + GGP_66[:4])
    assert out == b"ABIN\rBA 100 0\r" + reply(2, 1, 100, 10, 1)
    assert link.send(GGP_66[4:]) == reply(2, 1, 100, 10, 1)


def test_each_module_answers_only_lines_addressed_to_it():
    """3.4.2: "The address character is A when the module address is 1, B for modules with
    address 2"; bytes go to every module in ASCII mode, only the addressed one echoes and answers."""
    link = Link(VirtualModule("PD28-1021", address=1), VirtualModule("PD86-1180", address=2))
    assert link.send(ENTER_ASCII + request(2, 139)) == ENTERED + reply(2, 2, 100, 139, 0)
    assert link.send(b"BGGP 66, 0\r") == b"BGGP 66, 0\rBB 100 2\r"
    assert link.send(b"A GGP 66, 0\r") == b"A GGP 66, 0\rBA 100 1\r"
    assert link.send(b"CGGP 66, 0\r") == b""  # module 3 is not on the bus


def test_a_binary_module_next_to_an_ascii_module():
    """Every module reads the line in its own mode (3.4; TMCM-6212 manual 3.1 binary frames):
    a binary request to module 2 is answered while module 1 is in ASCII mode and stays silent."""
    link = Link(VirtualModule("PD28-1021", address=1), VirtualModule("PD86-1180", address=2))
    link.send(ENTER_ASCII)
    assert link.send(request(2, 10, 66, 0)) == reply(2, 2, 100, 10, 2)
    link.pause()
    assert link.send(b"\rAGGP 66, 0\r") == b"AGGP 66, 0\rBA 100 1\r"


def test_echo_modes_of_gp67_bits_4_and_5():
    """3.4.4: bits 4/5 both clear: every character echoed; bit 4: "the entire line will be echoed
    back after the <CR>"; bit 5: "no echo, only the reply will be sent"."""
    link = Link(VirtualModule("PD28-1021", address=1))
    link.send(ENTER_ASCII)
    assert link.send(b"AGG") == b"AGG"
    assert link.send(b"P 66, 0\r") == b"P 66, 0\rBA 100 1\r"
    link.send(b"ASGP 67, 0, 16\r")
    assert link.send(b"AGGP 66, 0") == b""
    assert link.send(b"\r") == b"AGGP 66, 0\rBA 100 1\r"
    link.send(b"ASGP 67, 0, 32\r")
    assert link.send(b"AGGP 66, 0\r") == b"BA 100 1\r"


def test_ascii_text_gets_no_telegram_pause():
    """GP75 "Pause time before the reply via RS485 is sent" delays binary replies; the echo of a
    typed character is sent at once (docs/assumptions.md)."""
    sleeps = []
    bus = ModuleBus([VirtualModule("PD28-1021", address=1)])
    session = SerialSession(bus, lambda b: None, gap=GAP, sleep=sleeps.append)
    session.receive(request(1, 9, 75, 0, 20))  # SGP 75, 0, 20
    assert sleeps == [pytest.approx(0.02)]
    session.receive(ENTER_ASCII)
    sleeps.clear()
    session.receive(b"AGGP 66, 0\r")
    assert sleeps == []


# --- real endpoints ---------------------------------------------------------------------------

@pytest.fixture
def ascii_pty(tmp_path):
    server = Server([VirtualModule("PD28-1021", address=1), VirtualModule("PD86-1180", address=2)])
    pty = server.add(PtyServer(server.bus, gap=GAP))
    server.start()
    try:
        with serial.Serial(pty.path, 9600, timeout=5) as port:
            yield server, port
    finally:
        server.stop()


def read_line(port) -> bytes:
    return port.read_until(b"\r")


@posix_only
def test_pty_ascii_session_with_the_manuals_reply(ascii_pty):
    """3.4.1 enter with 139; 3.4.3 "after sending AGAP 0, 1 the reply would be BA 100 -5000 if the
    actual position ... is -5000, the host address is set to 2 and the module address is 1"
    (one axis: motor 0); 3.4.4 character echo (GP67 = 0)."""
    _, port = ascii_pty
    port.write(ENTER_ASCII)
    assert port.read(9) == ENTERED
    port.write(b"ASAP 1, 0, -5000\r")
    assert read_line(port) == b"ASAP 1, 0, -5000\r"
    assert read_line(port) == b"BA 100 0\r"
    port.write(b"AGAP 1, 0\r")
    assert read_line(port) + read_line(port) == b"AGAP 1, 0\rBA 100 -5000\r"


@posix_only
def test_pty_echo_modes_backspace_and_bin(ascii_pty):
    """3.4.4 echo modes and "Characters can also be erased using the backspace character";
    3.4.1 BIN returns to binary mode: the manual's GGP 66, 0 frame is answered in binary."""
    _, port = ascii_pty
    port.write(ENTER_ASCII)
    assert port.read(9) == ENTERED
    port.write(b"AGAP 9\x084, 0\r")                       # backspace erases the 9
    assert read_line(port) == b"AGAP 9\x084, 0\r"
    assert read_line(port).startswith(b"BA 100 ")
    port.write(b"ASGP 67, 0, 16\r")                       # bit 4: whole line after <CR>
    assert read_line(port) + read_line(port) == b"ASGP 67, 0, 16\rBA 100 0\r"
    port.write(b"AGGP 66, 0")
    port.timeout = 0.2
    assert port.read(1) == b""                            # nothing echoed before <CR>
    port.timeout = 5
    port.write(b"\r")
    assert read_line(port) + read_line(port) == b"AGGP 66, 0\rBA 100 1\r"
    port.write(b"ASGP 67, 0, 32\r")                       # bit 5: reply only
    assert read_line(port) + read_line(port) == b"ASGP 67, 0, 32\rBA 100 0\r"
    port.write(b"AGGP 66, 0\r")
    assert read_line(port) == b"BA 100 1\r"
    port.write(b"ABIN\r")
    assert read_line(port) == b"BA 100 0\r"
    port.write(GGP_66)
    assert port.read(9) == reply(2, 1, 100, 10, 1)


@posix_only
def test_pty_two_modules_in_ascii_mode(ascii_pty):
    """3.4.2: to address module 2 "use address character B instead of A"; module 1 stays silent."""
    _, port = ascii_pty
    port.write(ENTER_ASCII + request(2, 139))
    assert port.read(18) == ENTERED + reply(2, 2, 100, 139, 0)
    port.write(b"BGGP 66, 0\r")
    assert read_line(port) + read_line(port) == b"BGGP 66, 0\rBB 100 2\r"
    port.write(b"ARUN\r")                                 # 3.4: RUN starts the TMCL program
    assert read_line(port) + read_line(port) == b"ARUN\rBA 100 0\r"
    port.write(b"ASTOP\r")
    assert read_line(port) + read_line(port) == b"ASTOP\rBA 100 0\r"


def test_tcp_ascii_mode():
    """The same over TCP (an Ethernet-to-serial converter carries the ASCII line unchanged):
    3.4.1 enter with 139, 3.4.3 reply, BIN back to binary (manual 3.6.8 GGP 66 frame)."""
    server = Server([VirtualModule("PD86-1180", address=1)])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0, gap=GAP))
    server.start()
    try:
        with socket.create_connection(tcp.address, timeout=5) as s:
            s.sendall(ENTER_ASCII)
            assert recv_exactly(s, 9) == ENTERED
            text = b"AGGP 66, 0\rBA 100 1\r"
            s.sendall(b"AGGP 66, 0\r")
            assert recv_exactly(s, len(text)) == text
            s.sendall(b"ABIN\r" + GGP_66)
            assert recv_exactly(s, 14 + 9) == b"ABIN\rBA 100 0\r" + reply(2, 1, 100, 10, 1)
    finally:
        server.stop()


def test_urlhandler_ascii_mode():
    """The opentmcl:// pyserial port reads ASCII lines as the other serial endpoints do (3.4)."""
    with serial.serial_for_url("opentmcl://PD28-1021", timeout=5) as port:
        port.write(ENTER_ASCII)
        assert port.read(9) == ENTERED
        port.write(b"ASGP 67, 0, 32\r")
        assert port.read_until(b"\r") == b"ASGP 67, 0, 32\r"
        assert port.read_until(b"\r") == b"BA 100 0\r"
        port.write(b"AGGP 66, 0\r")
        assert port.read_until(b"\r") == b"BA 100 1\r"


@posix_only
def test_gp67_bit0_starts_the_served_module_in_ascii_mode(serve, tmp_path):  # noqa: F811
    """3.4.4: "Bit 0 determines the startup mode: if this bit is set, the module will start up in
    ASCII mode". Set over the pty in binary (SGP 67, 0, 1), then the server is restarted with the
    same --eeprom file: the module answers text at once, and BIN returns to binary."""
    eeprom = str(tmp_path / "pd28.json")
    first = serve("--module", "PD28-1021", "--pty", "--eeprom", eeprom, "--gap", str(GAP))
    with serial.Serial(first.endpoint("pty"), timeout=5) as port:
        port.write(request(1, 9, 67, 0, 1))
        assert is_ok(port.read(9), 2, 1, 9)
    assert first.stop()[0] == 0
    second = serve("--module", "PD28-1021", "--pty", "--eeprom", eeprom, "--gap", str(GAP))
    assert any("ASCII mode" in line for line in second.lines)
    with serial.Serial(second.endpoint("pty"), timeout=5) as port:
        port.write(b"AGGP 67, 0\r")
        assert port.read_until(b"\r") + port.read_until(b"\r") == b"AGGP 67, 0\rBA 100 1\r"
        port.write(b"ABIN\r")
        assert port.read_until(b"\r") + port.read_until(b"\r") == b"ABIN\rBA 100 0\r"
        time.sleep(3 * GAP)
        port.write(GGP_66)
        assert port.read(9) == reply(2, 1, 100, 10, 1)
    assert second.stop()[0] == 0
