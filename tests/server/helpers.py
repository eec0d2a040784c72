"""Frames and helpers shared by the endpoint tests (all vectors from the manuals)."""
from __future__ import annotations

import socket
import time
import uuid

import serial

from opentmcl.lang import assemble
from opentmcl.protocol.frame import Reply, Request

WAIT = 30.0  # seconds a condition may take on a loaded machine; nothing here is timed

# TMCM-6212 manual 3.6.8 example: GGP 66, 0 -> 01 0A 42 00 00 00 00 00 4D
GGP_66 = bytes.fromhex("010A4200000000004D")
# TMCM-6212 manual 3.6.7 example: SGP 66, 0, 3 -> 01 09 42 00 00 00 00 03 4F
SGP_66_3 = bytes.fromhex("01094200000000034F")
# TMCM-6212 manual 3.6.35 example: command 138 type 1, motors #0 and #2 -> checksum 91
REQ_EVENT_0_2 = bytes.fromhex("018A0100000000 0591".replace(" ", ""))


def reply(host: int, module: int, status: int, command: int, value: int) -> bytes:
    """A reply frame as manual 3.2 lays it out (checksum per 3.1.1)."""
    return Reply(host, module, status, command, value).encode()


def request(address: int, command: int, type_: int = 0, motor: int = 0, value: int = 0) -> bytes:
    return Request(address, command, type_, motor, value).encode()


def recv_exactly(sock: socket.socket, n: int, timeout: float = 5.0) -> bytes:
    """Read n bytes from a socket; returns what came if the peer closed or time ran out."""
    deadline = time.monotonic() + timeout
    buf = bytearray()
    while len(buf) < n:
        left = deadline - time.monotonic()
        if left <= 0:
            break
        sock.settimeout(left)
        try:
            chunk = sock.recv(n - len(buf))
        except TimeoutError:
            break
        if not chunk:
            break
        buf += chunk
    return bytes(buf)


def drain_socket(sock: socket.socket, quiet: float = 0.15) -> bytes:
    """Read whatever arrives until the socket has been quiet for `quiet` seconds."""
    buf = bytearray()
    sock.settimeout(quiet)
    while True:
        try:
            chunk = sock.recv(4096)
        except TimeoutError:
            return bytes(buf)
        if not chunk:
            return bytes(buf)
        buf += chunk


def unique_channel() -> str:
    """A python-can virtual channel no other test uses."""
    return f"opentmcl-test-{uuid.uuid4().hex[:12]}"


def is_ok(frame: bytes, host: int, module: int, command: int) -> bool:
    """A well-formed status-100 reply (manual 3.2) whose value is "don't care" (e.g. SGP)."""
    return (len(frame) == 9 and frame[8] == sum(frame[:8]) & 0xFF
            and tuple(frame[:4]) == (host, module, 100, command))


def wait_handled(session, total: int, timeout: float = 30.0) -> None:
    """Until an endpoint's session has handled `total` received bytes (bounded).

    A test that pauses to make an inter-byte gap first waits for this: on a loaded machine the
    endpoint may read the bytes before the pause only after it, and then sees no gap at all."""
    deadline = time.monotonic() + timeout
    while session.bytes_received < total and time.monotonic() < deadline:
        time.sleep(0.002)
    assert session.bytes_received == total


def only_session(tcp, timeout: float = 10.0):
    """The session of the one client of a TcpServer, once it has been accepted (bounded)."""
    deadline = time.monotonic() + timeout
    while not tcp.sessions and time.monotonic() < deadline:
        time.sleep(0.002)
    [session] = tcp.sessions
    return session


class Link:
    """A host on a served port: whole 9-byte frames out, replies in (pyserial on the pty)."""

    def __init__(self, path: str, address: int = 1) -> None:
        self.port = serial.Serial(path, 9600, timeout=0.2)
        self.address = address
        self.unsolicited: list[Reply] = []

    def send(self, command: int, type_: int = 0, motor: int = 0, value: int = 0, address: int | None = None) -> None:
        self.port.write(Request(self.address if address is None else address, command, type_, motor,
                                value).encode())

    def read(self, n: int = 9) -> bytes:
        deadline, buf = time.monotonic() + WAIT, b""
        while len(buf) < n and time.monotonic() < deadline:
            buf += self.port.read(n - len(buf))
        assert len(buf) == n, f"wanted {n} bytes, got {buf!r}"
        return buf

    def reply(self) -> Reply:
        """The next reply; unsolicited ones (status 128, command 138) are set aside."""
        while True:
            r = Reply.decode(self.read())
            if r.status != 128:
                return r
            self.unsolicited.append(r)

    def ask(self, command: int, type_: int = 0, motor: int = 0, value: int = 0) -> Reply:
        self.send(command, type_, motor, value)
        r = self.reply()
        assert r.command == command
        return r

    def value(self, command: int, type_: int = 0, motor: int = 0, value: int = 0) -> int:
        r = self.ask(command, type_, motor, value)
        assert r.status == 100, r
        return r.value

    def until(self, command: int, type_: int, motor: int, want) -> int:
        """Poll until `want(value)` holds or WAIT has passed; the last value read."""
        deadline = time.monotonic() + WAIT
        while True:
            got = self.value(command, type_, motor)
            if want(got) or time.monotonic() > deadline:
                return got
            time.sleep(0.01)

    def download(self, source: str, module: str) -> list:
        """132, the assembled instructions (each status 101), 133 (manual 3.6.36)."""
        program = assemble(source, module=module).instructions
        assert self.ask(132).status == 100
        for ins in program:
            assert self.ask(ins.command, ins.type, ins.motor, ins.value).status == 101, ins
        assert self.ask(133).status == 100
        return program

    def close(self) -> None:
        self.port.close()
