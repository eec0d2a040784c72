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
    only_session,
    recv_exactly,
    reply,
    request,
    unique_channel,
    wait_handled,
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
            session = only_session(tcp)
            sent = [0]  # bytes sent so far (a reply is written before its bytes are counted)

            @ENDPOINT_SETTINGS
            @given(stream=streams)
            def check(stream):
                assume(not addresses_module_1(stream))
                sent[0] += len(stream)
                s.sendall(stream)
                wait_handled(session, sent[0])  # then the pause below is silence on the line
                time.sleep(3 * GAP)
                drain_socket(s, 0.05)
                sent[0] += len(GGP_66)
                s.sendall(GGP_66)
                assert read_check_reply(lambda: recv_exactly(s, 9)) == GOOD_REPLY

            check()
    finally:
        server.stop()


def test_fuzz_pty():
    server = Server([VirtualModule("TMCM-6212", address=1)])
    pty = server.add(PtyServer(server.bus, gap=GAP, interface="rs485"))  # frames for others ignored
    server.start()
    try:
        with serial.Serial(pty.path, timeout=5) as port:
            sent = [0]  # bytes sent so far (a reply is written before its bytes are counted)

            @ENDPOINT_SETTINGS
            @given(stream=streams)
            def check(stream):
                assume(not addresses_module_1(stream))
                sent[0] += len(stream)
                port.write(stream)
                port.flush()
                wait_handled(pty.session, sent[0])  # then the pause below is silence on the line
                time.sleep(3 * GAP)
                time.sleep(0.05)
                port.reset_input_buffer()
                sent[0] += len(GGP_66)
                port.write(GGP_66)
                assert read_check_reply(lambda: port.read(9)) == GOOD_REPLY

            check()
    finally:
        server.stop()


def test_fuzz_urlhandler():
    with serial.serial_for_url(f"opentmcl://TMCM-6212?gap={GAP}&interface=rs485", timeout=5) as port:

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


# --- ASCII mode (PD28-1021 manual 3.4, PD86-1180 manual 4.5) ---------------------------------

ENTER_ASCII = request(1, 139)      # binary command 139: enter ASCII mode
ASCII_VECTORS = [                  # the manual's command lines (3.4.2) and a few more
    b"AMVP ABS, 1, 50000\r", b"A MVP ABS, 1, 50000\r", b"AROL 2, 500\r", b"A MST 1\r", b"ABIN\r",
    b"AGAP 1, 0\r", b"AGGP 66, 0\r", b"ARUN\r", b"ASTOP\r", b"BGAP 1, 0\r", b"ASGP 67, 0, 16\r",
    b"ASGP 67, 0, 32\r", b"ASAP 4, 0, 1000\r", b"A GAP 9\x08\x084, 0\r", b"AFOO\r", b"\r",
    b"ABIN\r" + GGP_66, b"ABIN\r" + ENTER_ASCII + b"AGGP 66, 0\r",
]
TEXT = st.binary(max_size=20) | st.text(alphabet="ABGPSMVRUNT0123456789 ,-\r\n\x08\x7f", max_size=20).map(
    str.encode)


@st.composite
def mutated_line(draw):
    """A manual command line with a changed, removed or inserted character, or cut short."""
    line = bytearray(draw(st.sampled_from(ASCII_VECTORS)))
    op = draw(st.sampled_from(["keep", "flip", "drop", "insert", "truncate"]))
    if op == "flip" and line:
        line[draw(st.integers(0, len(line) - 1))] = draw(st.integers(0, 255))
    elif op == "drop" and line:
        del line[draw(st.integers(0, len(line) - 1))]
    elif op == "insert":
        line.insert(draw(st.integers(0, len(line))), draw(st.sampled_from([8, 127, 10, 13, 32, 0, 255])))
    elif op == "truncate":
        line = line[:draw(st.integers(0, len(line)))]
    return bytes(line)


ascii_streams = st.lists(st.one_of(mutated_line(), TEXT, st.just(ENTER_ASCII), mutated_frame()),
                         max_size=10).map(b"".join)


def reference_output(vm, data: bytes) -> bytes:
    """What one module answers to `data` arriving in one piece: 9-byte frames in binary mode
    (TMCM-6212 manual 3.1), text in ASCII mode (3.4), the bytes after a BIN line binary again."""
    out, frame, pos = bytearray(), b"", 0
    while pos < len(data):
        if vm.ascii_mode:
            out += vm.feed_ascii(data[pos:])
            if vm.ascii_mode:
                break
            pos, frame = len(data) - len(vm.ascii.leftover), b""
            continue
        take = data[pos:pos + 9 - len(frame)]
        frame, pos = frame + take, pos + len(take)
        if len(frame) == 9:
            out += vm.handle(frame)
            frame = b""
    return bytes(out)


def cut(stream: bytes, cuts: list[int]) -> list[bytes]:
    """`stream` split at the given offsets (taken modulo its length)."""
    points = sorted({c % (len(stream) + 1) for c in cuts} | {0, len(stream)})
    return [stream[a:b] for a, b in zip(points, points[1:], strict=False)]


@given(stream=ascii_streams, cuts=st.lists(st.integers(0, 400), max_size=6),
       name=st.sampled_from(["PD28-1021", "PD86-1180"]))
def test_session_in_ascii_mode_matches_the_module(stream, cuts, name):
    """Any mix of command lines, text, 139 frames and binary garbage, cut anywhere: the session
    writes exactly what the module itself answers to the whole stream (echo, replies, BIN and 139
    switching modes), and never raises."""
    written = bytearray()
    bus = ModuleBus([VirtualModule(name, address=1)], clock=lambda: 0.0)
    session = SerialSession(bus, written.extend, gap=GAP, clock=lambda: 0.0, sleep=lambda s: None)
    reference = VirtualModule(name, address=1)
    session.receive(ENTER_ASCII)
    reference.handle(ENTER_ASCII)
    written.clear()
    for chunk in cut(stream, cuts):
        session.receive(chunk)
    assert bytes(written) == reference_output(reference, stream)
    assert bus.modules[0].ascii_mode == reference.ascii_mode


@given(stream=ascii_streams)
def test_two_ascii_modules_never_raise_and_stay_reachable(stream):
    """Two modules in ASCII mode on one line (3.4.2: each answers its own address character):
    after any stream, a <CR> and a pause, each module answers its own GGP 66 line or frame."""
    t = [0.0]
    written = bytearray()
    modules = [VirtualModule("PD28-1021", address=1), VirtualModule("PD86-1180", address=2)]
    bus = ModuleBus(modules, clock=lambda: t[0])
    session = SerialSession(bus, written.extend, gap=GAP, clock=lambda: t[0], sleep=lambda s: None)
    session.receive(ENTER_ASCII + request(2, 139))
    session.receive(stream)
    for vm in modules:
        t[0] += 10 * GAP
        session.receive(b"\r")  # ends a partial text line (binary mode: a partial frame, dropped below)
        t[0] += 10 * GAP
        address = vm.address
        written.clear()
        if vm.ascii_mode:
            vm.globals.set(0, 67, 0x20)  # bit 5: reply only
            letter = chr(ord("A") + address - 1).encode()
            session.receive(letter + b"GGP 66, 0\r")
            assert bytes(written).endswith(b"B" + letter + b" 100 %d\r" % address)
        else:
            session.receive(request(address, 10, 66, 0))
            assert bytes(written).endswith(reply(2, address, 100, 10, address))


def safe_ascii_stream(stream: bytes) -> bool:
    """No S (no SGP/STGP/SAP/SIO: address, echo and host address stay as they are) and no valid
    binary request to module 1 other than 139 (enter ASCII mode)."""
    if b"S" in stream.upper():
        return False
    return not any(stream[i] == 1 and checksum(stream[i:i + 8]) == stream[i + 8] and stream[i:i + 9] != ENTER_ASCII
                   for i in range(len(stream) - 8))


def wait_consumed(session, total: int) -> None:
    """Until the endpoint has handled `total` bytes (bounded: 30 s)."""
    wait_handled(session, total)


def ascii_check(vm, write, read_all, read_n):
    """After any stream: a pause, then the module answers in the mode it is in."""
    time.sleep(3 * GAP)
    if vm.ascii_mode:
        write(b"\r")                          # ends a partial line
        time.sleep(3 * GAP)
        read_all()
        write(b"AGGP 66, 0\r")                 # 3.4.4 character echo (GP67 = 0), 3.4.3 reply
        expected = b"AGGP 66, 0\rBA 100 1\r"
        assert read_n(len(expected)) == expected
    else:
        read_all()
        write(GGP_66)
        assert read_check_reply(lambda: read_n(9)) == GOOD_REPLY


def test_fuzz_ascii_pty():
    server = Server([VirtualModule("PD28-1021", address=1)])
    pty = server.add(PtyServer(server.bus, gap=GAP, interface="rs485"))  # frames for others ignored
    server.start()
    vm = server.modules[0]
    try:
        with serial.Serial(pty.path, timeout=5) as port:
            port.write(ENTER_ASCII)
            assert port.read(9) == reply(2, 1, 100, 139, 0)
            wait_consumed(pty.session, len(ENTER_ASCII))  # counted after its reply is written

            def read_all():
                time.sleep(0.05)
                port.reset_input_buffer()

            def write(data):
                total = pty.session.bytes_received + len(data)
                port.write(data)
                port.flush()
                wait_consumed(pty.session, total)  # the mode is read after the bytes are handled

            @ENDPOINT_SETTINGS
            @given(stream=ascii_streams)
            def check(stream):
                assume(safe_ascii_stream(stream))
                write(stream)
                ascii_check(vm, write, read_all, port.read)

            check()
    finally:
        server.stop()


def test_fuzz_ascii_tcp():
    import socket

    server = Server([VirtualModule("PD86-1180", address=1)])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0, gap=GAP))
    server.start()
    vm = server.modules[0]
    try:
        with socket.create_connection(tcp.address, timeout=5) as s:
            s.sendall(ENTER_ASCII)
            assert recv_exactly(s, 9) == reply(2, 1, 100, 139, 0)
            session = only_session(tcp)
            wait_consumed(session, len(ENTER_ASCII))  # counted after its reply is written

            def write(data):
                total = session.bytes_received + len(data)
                s.sendall(data)
                wait_consumed(session, total)  # the mode is read after the bytes are handled

            @ENDPOINT_SETTINGS
            @given(stream=ascii_streams)
            def check(stream):
                assume(safe_ascii_stream(stream))
                write(stream)
                ascii_check(vm, write, lambda: drain_socket(s, 0.05), lambda n: recv_exactly(s, n))

            check()
    finally:
        server.stop()


def test_fuzz_ascii_urlhandler():
    with serial.serial_for_url(f"opentmcl://PD28-1021?gap={GAP}", timeout=5) as port:
        vm = port.modules[0]
        port.write(ENTER_ASCII)
        assert port.read(9) == reply(2, 1, 100, 139, 0)

        @ENDPOINT_SETTINGS
        @given(stream=ascii_streams)
        def check(stream):
            assume(safe_ascii_stream(stream))
            port.write(stream)
            ascii_check(vm, port.write, port.reset_input_buffer, port.read)

        check()
