"""Fuzzing every endpoint with random and mutated frames (hypothesis).

The invariant of the issue: the server never dies, and after the garbage (and an
inter-byte gap) every well-formed request still gets the correct reply. The check
request is the manual's GGP 66, 0 example (TMCM-6212 manual 3.6.8), reply per 3.2.
"""
import time

import can
import serial
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import opentmcl.urlhandler  # noqa: F401
from opentmcl import VirtualModule
from opentmcl.protocol.frame import checksum
from opentmcl.server import CanServer, PtyServer, Server, TcpServer
from opentmcl.server.bus import ModuleBus
from opentmcl.server.session import SerialSession

from .helpers import (
    GGP_66,
    REQ_EVENT_0_2,
    SGP_66_3,
    drain_socket,
    recv_exactly,
    reply,
    request,
    unique_channel,
)

GAP = 0.03
GOOD_REPLY = reply(2, 1, 100, 10, 1)
WRONG_CHECKSUM = 1  # manual 3.2.1 status 1


def read_check_reply(read9) -> bytes:
    """The reply to the check request, past late status-1 replies to mangled frames."""
    got = read9()
    while len(got) == 9 and got[2] == WRONG_CHECKSUM:
        got = read9()
    return got
VECTORS = [GGP_66, SGP_66_3, REQ_EVENT_0_2, request(1, 4, 0, 0, 1000), request(1, 1, 0, 0, 5000),
           request(1, 136, 0, 0, 0), request(1, 9, 255, 0, 1)]
# Real sockets and ptys cost a gap per example: half the profile's examples (30 with "ci",
# 2500 with HYPOTHESIS_PROFILE=long).
ENDPOINT_SETTINGS = settings(max_examples=max(10, settings.default.max_examples // 2), deadline=None,
                             suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


@st.composite
def mutated_frame(draw):
    """A manual-derived request with byte flips, truncation, a new address or stray bytes."""
    frame = bytearray(draw(st.sampled_from(VECTORS)))
    op = draw(st.sampled_from(["flip", "truncate", "readdress", "insert", "checksum_ok"]))
    if op == "flip":
        i = draw(st.integers(0, 8))
        frame[i] ^= draw(st.integers(1, 255))
    elif op == "truncate":
        frame = frame[:draw(st.integers(0, 8))]
    elif op == "readdress":
        frame[0] = draw(st.integers(0, 255))
        frame[8] = checksum(frame[:8])
    elif op == "insert":
        i = draw(st.integers(0, 9))
        frame[i:i] = draw(st.binary(min_size=1, max_size=4))
    else:
        frame[1:8] = draw(st.binary(min_size=7, max_size=7))
        frame[8] = checksum(frame[:8])
    return bytes(frame)


streams = st.lists(st.one_of(st.binary(max_size=30), mutated_frame()), max_size=8).map(b"".join)


def addresses_module_1(stream: bytes) -> bool:
    """Does any 9-byte window form a valid request to address 1 (a real command)?"""
    return any(stream[i] == 1 and checksum(stream[i:i + 8]) == stream[i + 8] for i in range(len(stream) - 8))


# --- pure level: framer + bus + session, every frame allowed ------------------------

@given(chunks=st.lists(st.one_of(st.binary(max_size=30), mutated_frame()), max_size=10))
def test_session_never_raises_and_matches_the_module(chunks):
    """Any stream, including valid commands that change state: the session passes the
    module exactly the frames of the stream and writes exactly the module's replies; a
    well-formed request after a gap is answered as the module itself answers it."""
    t = [0.0]
    written = []
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)], clock=lambda: t[0])
    session = SerialSession(bus, written.append, gap=GAP, clock=lambda: t[0], sleep=lambda s: None)
    reference = VirtualModule("TMCM-6212", address=1)
    expected = []
    stream = b""
    for chunk in chunks:
        session.receive(chunk)
        stream += chunk
    for i in range(0, len(stream) - len(stream) % 9, 9):
        out = reference.handle(stream[i:i + 9])
        if out:
            expected.append(out)
    assert b"".join(written) == b"".join(expected)
    t[0] += 10 * GAP
    written.clear()
    session.receive(GGP_66)
    assert b"".join(written) == reference.handle(GGP_66)


# --- real endpoints ----------------------------------------------------------------------

def test_fuzz_tcp():
    server = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0, gap=GAP))
    server.start()
    try:
        import socket

        with socket.create_connection(tcp.address, timeout=5) as s:

            @ENDPOINT_SETTINGS
            @given(stream=streams)
            def check(stream):
                assume(not addresses_module_1(stream))
                s.sendall(stream)
                time.sleep(3 * GAP)
                drain_socket(s, 0.05)
                s.sendall(GGP_66)
                assert read_check_reply(lambda: recv_exactly(s, 9)) == GOOD_REPLY

            check()
    finally:
        server.stop()


def test_fuzz_pty():
    server = Server([VirtualModule("TMCM-6212", address=1)])
    pty = server.add(PtyServer(server.bus, gap=GAP))
    server.start()
    try:
        with serial.Serial(pty.path, timeout=5) as port:

            @ENDPOINT_SETTINGS
            @given(stream=streams)
            def check(stream):
                assume(not addresses_module_1(stream))
                port.write(stream)
                port.flush()
                time.sleep(3 * GAP)
                time.sleep(0.05)
                port.reset_input_buffer()
                port.write(GGP_66)
                assert read_check_reply(lambda: port.read(9)) == GOOD_REPLY

            check()
    finally:
        server.stop()


def test_fuzz_urlhandler():
    with serial.serial_for_url(f"opentmcl://TMCM-6212?gap={GAP}", timeout=5) as port:

        @ENDPOINT_SETTINGS
        @given(stream=streams)
        def check(stream):
            assume(not addresses_module_1(stream))
            port.write(stream)
            time.sleep(3 * GAP)
            port.reset_input_buffer()
            port.write(GGP_66)
            assert port.read(9) == GOOD_REPLY

        check()


can_frames = st.lists(st.tuples(st.integers(0, 0x7FF), st.binary(max_size=8), st.booleans(), st.booleans()),
                      max_size=8)


def test_fuzz_can():
    channel = unique_channel()
    server = Server([VirtualModule("TMCM-6212", address=1)])
    server.add(CanServer(server.bus, "virtual", channel))
    server.start()
    host = can.Bus(interface="virtual", channel=channel)
    try:

        @ENDPOINT_SETTINGS
        @given(frames=can_frames)
        def check(frames):
            for can_id, data, extended, remote in frames:
                # a 7/8-byte standard data frame to ID 1 is a real command: keep state intact
                assume(extended or remote or can_id != 1 or len(data) not in (7, 8))
            for can_id, data, extended, remote in frames:
                if remote:
                    msg = can.Message(arbitration_id=can_id, is_remote_frame=True, dlc=len(data),
                                      is_extended_id=extended)
                else:
                    msg = can.Message(arbitration_id=can_id, data=data, is_extended_id=extended)
                host.send(msg)
            while host.recv(0.05) is not None:
                pass
            host.send(can.Message(arbitration_id=1, data=GGP_66[1:8], is_extended_id=False))
            got = host.recv(5)
            assert got is not None and got.arbitration_id == 2
            assert bytes(got.data) == bytes([1, 100, 10, 0, 0, 0, 1])

        check()
    finally:
        host.shutdown()
        server.stop()
