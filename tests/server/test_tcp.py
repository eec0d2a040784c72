"""TCP endpoint and TCP host transport: raw 9-byte frames over a socket."""
import socket
import threading
import time
import urllib.parse

import pytest

from opentmcl import VirtualModule
from opentmcl.host.errors import TmclConnectionError, TmclTimeout
from opentmcl.host.transports.tcp import TcpTransport, open_tcp
from opentmcl.server import Server
from opentmcl.server.tcp import TcpServer, is_loopback

from .conftest import GAP
from .helpers import (
    GGP_66,
    REQ_EVENT_0_2,
    SGP_66_3,
    drain_socket,
    is_ok,
    only_session,
    recv_exactly,
    reply,
    request,
    wait_handled,
)


def connect(tcp):
    return socket.create_connection(tcp.address, timeout=5)


def test_manual_example_over_tcp(tcp_server):
    """Manual 3.6.8 GGP 66, 0 example sent as raw bytes, as an Ethernet-to-serial
    converter carries them; the reply is the 9-byte frame of manual 3.2."""
    _, tcp = tcp_server
    with connect(tcp) as s:
        s.sendall(GGP_66)
        assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)


def test_transport_roundtrip_and_url(tcp_server):
    """Manual 3.6.7 SGP 66, 0, 3 example then GGP 66 at the new address 3."""
    _, tcp = tcp_server
    host, port = tcp.address
    t = open_tcp(urllib.parse.urlsplit(f"tcp://{host}:{port}"))
    try:
        t.send(SGP_66_3)
        got = t.recv(9, 5)
        assert got[2:4] == bytes([100, 9])  # status 100 for SGP; the value is "don't care" (3.6.7)
        t.send(request(3, 10, 66, 0))
        assert t.recv(9, 5) == reply(2, 3, 100, 10, 3)
    finally:
        t.close()
        t.close()  # idempotent


def test_garbage_and_truncated_frame_resynchronise_after_gap(tcp_server):
    """A truncated command and garbage never wedge the port: after an inter-byte gap the
    next well-formed request (manual 3.6.8 example) gets its reply."""
    _, tcp = tcp_server
    with connect(tcp) as s:
        session = only_session(tcp)
        s.sendall(GGP_66[:5])
        wait_handled(session, 5)
        time.sleep(GAP * 3)
        s.sendall(GGP_66)
        assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)
        s.sendall(b"\x00\x13\x37")
        wait_handled(session, 17)
        time.sleep(GAP * 3)
        s.sendall(GGP_66)
        assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)


def test_wrong_checksum_answers_status_1(tcp_server):
    """Manual 3.2.1 status 1 "Wrong checksum"."""
    _, tcp = tcp_server
    with connect(tcp) as s:
        s.sendall(GGP_66[:8] + b"\x00")
        got = recv_exactly(s, 9)
        assert got[:3] == bytes([2, 1, 1])


def test_other_address_is_ignored_silently(tcp_server):
    """Manual 5.1 GP66: frames for other addresses get no reply at all."""
    _, tcp = tcp_server
    with connect(tcp) as s:
        s.sendall(request(2, 10, 66, 0))
        assert drain_socket(s, 0.3) == b""
        s.sendall(GGP_66)
        assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)


def test_position_reached_event_reaches_the_tcp_client(tcp_server):
    """Manual 3.6.35: command 138 then MVP; the additional reply (status 128, motor mask)
    follows when the motor arrives, in real time."""
    _, tcp = tcp_server
    with connect(tcp) as s:
        s.sendall(REQ_EVENT_0_2)
        assert recv_exactly(s, 9) == reply(2, 1, 100, 138, 5)
        s.sendall(request(1, 4, 0, 0, 100))  # MVP ABS, 0, 100: a short move
        assert is_ok(recv_exactly(s, 9), 2, 1, 4)  # MVP reply value: "don't care" (3.6.4)
        assert recv_exactly(s, 9, timeout=10) == reply(2, 1, 128, 138, 1)


def test_bounded_number_of_clients(tcp_server):
    """Safety (docs/endpoints.md): at most max_clients at once; a further client is closed."""
    _, tcp = tcp_server
    with connect(tcp) as a, connect(tcp) as b:
        for s in (a, b):
            s.sendall(GGP_66)
            assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)
        with connect(tcp) as c:
            c.settimeout(5)
            assert c.recv(9) == b""
    # a slot frees when a client leaves
    deadline = time.monotonic() + 5
    while tcp.client_count and time.monotonic() < deadline:
        time.sleep(0.01)
    with connect(tcp) as d:
        d.sendall(GGP_66)
        assert recv_exactly(d, 9) == reply(2, 1, 100, 10, 1)


class AbortOnce:
    """The listening socket, except that its next accept() fails as when a client resets its
    connection before the server accepts it (ECONNABORTED)."""

    def __init__(self, sock):
        self.sock = sock
        self.failed = threading.Event()

    def accept(self):
        if not self.failed.is_set():
            self.failed.set()
            raise ConnectionAbortedError(103, "Software caused connection abort")
        return self.sock.accept()

    def __getattr__(self, name):
        return getattr(self.sock, name)


def test_a_failed_accept_does_not_stop_the_endpoint(tcp_server):
    """docs/architecture.md "Errors": the server never dies. A failed accept leaves the TCP
    endpoint listening; the next client gets its reply to the manual 3.6.8 GGP 66 example."""
    _, tcp = tcp_server
    tcp._sock = AbortOnce(tcp._sock)
    assert tcp._sock.failed.wait(5)
    with connect(tcp) as s:
        s.sendall(GGP_66)
        assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)


def test_loopback_detection():
    assert is_loopback("127.0.0.1") and is_loopback("::1") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.2")


def test_default_bind_is_loopback():
    """Safety: a TcpServer binds 127.0.0.1 unless told otherwise."""
    assert TcpServer(bus=None).host == "127.0.0.1"


def test_transport_errors_are_typed(tcp_server):
    """Host transport: connection refused -> TmclConnectionError; silence -> TmclTimeout."""
    _, tcp = tcp_server
    free = socket.socket()
    free.bind(("127.0.0.1", 0))
    port = free.getsockname()[1]
    free.close()
    with pytest.raises(TmclConnectionError):
        TcpTransport("127.0.0.1", port, connect_timeout=2)
    t = TcpTransport(*tcp.address)
    try:
        t.send(request(9, 10, 66, 0))  # nobody at address 9
        with pytest.raises(TmclTimeout):
            t.recv(9, 0.2)
    finally:
        t.close()
    with pytest.raises(TmclConnectionError):
        t.send(GGP_66)


def test_transport_reports_server_going_away(tcp_server):
    server, tcp = tcp_server
    t = TcpTransport(*tcp.address)
    try:
        server.stop()
        with pytest.raises(TmclConnectionError):
            t.recv(9, 5)
    finally:
        t.close()


@pytest.mark.parametrize("url", ["tcp://", "tcp://host", "tcp://127.0.0.1:99999", "tcp://h:1?connect_timeout=x",
                                 "tcp://h:1?connect_timeout=-1", "tcp://h:1?connect_timeout=nan"])
def test_bad_tcp_urls(url):
    with pytest.raises(TmclConnectionError):
        open_tcp(urllib.parse.urlsplit(url))


class FaultyModule(VirtualModule):
    """A module with a bug: it raises on command 200 instead of answering status 2."""

    def handle(self, frame):
        if len(frame) == 9 and frame[1] == 200:
            raise RuntimeError("simulated firmware bug")
        return super().handle(frame)


def test_a_module_bug_does_not_kill_the_endpoint():
    """docs/architecture.md "Errors": the server never dies; the link keeps answering
    well-formed requests (manual 3.6.8 example) after a frame that made the module raise."""
    server = Server([FaultyModule("TMCM-6212", address=1)])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0, gap=GAP))
    server.start()
    try:
        with connect(tcp) as s:
            s.sendall(request(1, 200))
            assert drain_socket(s, 0.2) == b""
            s.sendall(GGP_66)
            assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)
    finally:
        server.stop()


def test_a_client_that_never_reads_is_dropped_and_others_are_served(tcp_server, caplog):
    """Safety (docs/endpoints.md): a client whose replies pile up unread for the send time-out is
    disconnected (and logged) instead of blocking the server; another client is then answered
    (manual 3.6.8 GGP 66 example as the probe)."""
    caplog.set_level("WARNING", logger="opentmcl.server")
    _, tcp = tcp_server
    lazy = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    lazy.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)   # fills quickly
    lazy.settimeout(1)
    lazy.connect(tcp.address)
    lazy.sendall(GGP_66)
    assert recv_exactly(lazy, 9) == reply(2, 1, 100, 10, 1)    # accepted and served
    assert tcp.client_count == 1
    burst = GGP_66 * 200
    deadline = time.monotonic() + 60
    dropped = False
    try:
        while not dropped and time.monotonic() < deadline:
            try:
                lazy.sendall(burst)                   # never reads a reply
            except (TimeoutError, OSError):
                pass
            dropped = tcp.client_count == 0
        sessions = tcp.sessions
        assert dropped, (f"still connected; framer dropped {sessions[0].framer.dropped} bytes"
                         if sessions else "still connected")
    finally:
        lazy.close()
    assert any("does not read its replies" in r.getMessage() for r in caplog.records)
    with connect(tcp) as other:
        other.sendall(GGP_66)
        assert recv_exactly(other, 9) == reply(2, 1, 100, 10, 1)


def test_accepted_sockets_use_tcp_keepalive(tcp_server):
    """Issue 11 problem 3: a half-open connection from a host that vanished must not hold a slot for
    ever. The accepted socket has SO_KEEPALIVE on and, where the platform has the options, probes
    after 60 s of silence every 10 s, 5 times (docs/endpoints.md)."""
    _, tcp = tcp_server
    with connect(tcp) as s:
        s.sendall(GGP_66)
        assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)
        with tcp._lock:
            (conn,) = tcp._clients
        assert conn.getsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE) != 0
        for name, value in (("TCP_KEEPIDLE", 60), ("TCP_KEEPINTVL", 10), ("TCP_KEEPCNT", 5)):
            if hasattr(socket, name):
                assert conn.getsockopt(socket.IPPROTO_TCP, getattr(socket, name)) == value


def test_refused_clients_are_logged_without_flooding_the_log(tcp_server, caplog, monkeypatch):
    """Issue 11 "a log line when a client is refused": with both slots of max_clients=2 held, each
    further client is refused; a burst within the log interval gives one line, the next line
    counts the refusals it left out."""
    import opentmcl.server.tcp as tcp_module

    caplog.set_level("WARNING", logger="opentmcl.server")
    monkeypatch.setattr(tcp_module, "REFUSED_LOG_EVERY", 3600.0)  # the whole burst is within it
    _, tcp = tcp_server
    with connect(tcp) as a, connect(tcp) as b:
        for s in (a, b):
            s.sendall(GGP_66)
            assert recv_exactly(s, 9) == reply(2, 1, 100, 10, 1)
        for _ in range(5):
            with connect(tcp) as c:
                c.settimeout(5)
                assert c.recv(9) == b""
        monkeypatch.setattr(tcp_module, "REFUSED_LOG_EVERY", 0.0)  # the interval is over
        with connect(tcp) as c:
            c.settimeout(5)
            assert c.recv(9) == b""
        deadline = time.monotonic() + 5
        while tcp.rejected < 6 and time.monotonic() < deadline:
            time.sleep(0.01)
    lines = [r.getMessage() for r in caplog.records if "refused" in r.getMessage()]
    assert tcp.rejected == 6 and len(lines) == 2
    assert lines[0].startswith("TCP client 127.0.0.1:") and "2 clients connected" in lines[0]
    assert lines[1].endswith("(4 more refused since the last line)")


def test_idle_timeout_must_be_finite_and_not_negative():
    """docs/endpoints.md: 0 means no idle timeout; otherwise a positive, finite number of seconds."""
    bus = Server([VirtualModule("TMCM-6212", address=1)]).bus
    for bad in (-1, -0.001, float("nan"), float("inf"), "5", None, True):
        with pytest.raises(ValueError):
            TcpServer(bus, "127.0.0.1", 0, idle_timeout=bad)
    assert TcpServer(bus, "127.0.0.1", 0, idle_timeout=0).idle_timeout == 0
    assert TcpServer(bus, "127.0.0.1", 0, idle_timeout=0.001).idle_timeout == 0.001
