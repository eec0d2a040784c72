"""The dashboard's connection limits (docs/dashboard.md, "Threat model"; issue 11 problem 3 for the
web server): a connection that never completes a request head is closed, a body that never
completes is refused with 408, and connections beyond the cap are closed at once, so idle or
trickling clients cannot hold the process's file descriptors for ever. Real sockets throughout;
the first test runs a real `opentmcl dashboard` process with its default limits."""
from __future__ import annotations

import socket
import urllib.parse

import pytest

from .rawhttp import get_json, page_headers, post_json, read_reply, request, start_cli, stop_cli

pytest.importorskip("uvicorn", reason="the dashboard needs the web extra")

HEAD_TIMEOUT = 10.0     # docs/dashboard.md: a request head must be complete within 10 s
GENEROUS = 60.0         # socket timeouts: far above the limit under test, never a timing assert


def closed_by_server(sock: socket.socket) -> bool:
    """True when the server closes `sock` (EOF or reset) before GENEROUS seconds pass."""
    sock.settimeout(GENEROUS)
    try:
        return sock.recv(1024) == b""
    except ConnectionResetError:
        return True


def test_the_cli_dashboard_closes_silent_and_half_sent_heads():
    """`opentmcl dashboard`: one connection sends nothing, one sends half a request head (slowloris);
    both are closed by the server, each with a log line, while a normal request is answered."""
    proc, url, _ = start_cli(["dashboard", "--to", "sim://TMCM-6212", "--web", "127.0.0.1:0"], "dashboard for")
    port = urllib.parse.urlsplit(url).port
    try:
        silent = socket.create_connection(("127.0.0.1", port))
        half = socket.create_connection(("127.0.0.1", port))
        half.sendall(b"GET /m/1/api/state HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: 1")
        assert get_json(port, "/api/modules")[0]["module"] == "TMCM-6212"
        assert closed_by_server(silent) and closed_by_server(half)
        silent.close()
        half.close()
    finally:
        out = stop_cli(proc)
    assert out.count(f"no complete request within {HEAD_TIMEOUT:g} s") >= 1, out
    assert "Traceback" not in out


@pytest.fixture
def limited():
    """A dashboard (real uvicorn on a real port) with small limits: 4 connections, 2 s for a body."""
    import opentmcl
    from opentmcl.web import start_dashboard

    module = opentmcl.connect("sim://TMCM-6212?clock=real")
    handle = start_dashboard(module, "127.0.0.1", 0, on_stop=module.close, poll=False,
                             max_connections=4, body_timeout=2.0, head_timeout=30.0)
    try:
        yield handle.port
    finally:
        handle.stop()


def test_connections_beyond_the_cap_are_closed_and_the_slots_come_back(limited):
    """Three idle connections and a fourth that asks: answered (the last slot). A fifth while four
    are open is closed at once; after the idle ones go, requests are answered again."""
    port = limited
    idle = [socket.create_connection(("127.0.0.1", port)) for _ in range(3)]
    fourth = socket.create_connection(("127.0.0.1", port), timeout=GENEROUS)
    fourth.sendall(f"GET /api/modules HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
    assert read_reply(fourth).status == 200       # kept alive: still counts as open
    fifth = socket.create_connection(("127.0.0.1", port))
    assert closed_by_server(fifth)
    for sock in (*idle, fourth, fifth):
        sock.close()
    assert get_json(port, "/api/modules")[0]["address"] == 1


def test_a_body_that_never_completes_is_refused_and_changes_nothing(limited):
    """POST program/run with Content-Length 100 and 10 bytes sent: 408 with a one-line reason after
    the body timeout, and the program does not start (manual 3.6.36, command 129)."""
    port = limited
    assert post_json(port, "/m/1/api/program/download", {"source": "Loop:\n    JA Loop\n"}).status == 200
    head = ["POST /m/1/api/program/run HTTP/1.1", f"Host: 127.0.0.1:{port}", "Content-Length: 100"]
    head += [f"{k}: {v}" for k, v in page_headers(port).items()]
    with socket.create_connection(("127.0.0.1", port), timeout=GENEROUS) as sock:
        sock.sendall(("\r\n".join(head) + "\r\n\r\n").encode() + b'{"x": 1, "')
        reply = read_reply(sock, "POST")
    assert reply.status == 408, reply.body[:200]
    assert "not complete within 2 s" in reply.error and "\n" not in reply.error
    assert get_json(port, "/m/1/api/program")["state"]["mode_name"] == "stop"
    assert request(port, "POST", "/m/1/api/program/stop", headers=page_headers(port)).status == 200


def test_an_open_websocket_is_not_taken_for_a_silent_connection():
    """The head timeout ends with the upgrade: a WebSocket (which sends nothing, docs/dashboard.md)
    keeps streaming well past it."""
    import time

    import opentmcl
    from opentmcl.web import start_dashboard

    from .rawhttp import WS_KEY

    module = opentmcl.connect("sim://TMCM-6212?clock=real")
    with start_dashboard(module, "127.0.0.1", 0, on_stop=module.close, head_timeout=0.5) as handle:
        port = handle.port
        with socket.create_connection(("127.0.0.1", port), timeout=GENEROUS) as sock:
            sock.sendall((f"GET /m/1/ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
                          f"Connection: Upgrade\r\nSec-WebSocket-Key: {WS_KEY}\r\nSec-WebSocket-Version: 13\r\n"
                          f"Origin: http://127.0.0.1:{port}\r\nSec-WebSocket-Protocol: opentmcl\r\n\r\n").encode())
            assert sock.recv(12).startswith(b"HTTP/1.1 101")
            time.sleep(2.0)                              # four head timeouts
            sock.recv(1 << 20)                           # what came so far
            assert sock.recv(1024) != b""                # and it is still streaming


def test_a_refused_websocket_logs_its_reason_and_no_error():
    """`opentmcl serve --web`: a WebSocket upgrade with a foreign Origin gets 403 with the reason and
    one warning line; the console shows no ERROR line for it (uvicorn's sans-I/O protocol logged
    "ASGI callable returned without completing handshake." at ERROR after each refusal)."""
    from .rawhttp import ws_upgrade

    proc, url, _ = start_cli(["serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--web", "127.0.0.1:0"],
                             "dashboard http")
    port = urllib.parse.urlsplit(url).port
    try:
        reply = ws_upgrade(port, "/m/1/ws", origin="http://evil.example")
        assert reply.status == 403 and "Origin" in reply.error
        assert ws_upgrade(port, "/m/1/ws", protocol=None).status == 403
    finally:
        out = stop_cli(proc)
    assert out.count("refused WEBSOCKET /m/1/ws") == 2, out
    assert "ERROR" not in out and "Traceback" not in out, out
