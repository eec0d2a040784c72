"""The dashboard's connection limits (docs/dashboard.md, "Threat model"; issue 11 problem 3 for the
web server): a connection that never completes a request head is closed, a body that never
completes is refused with 408, and the connections are capped, so idle or trickling clients cannot
hold the process's file descriptors for ever; beyond the cap an idle connection gives its place to
a new one, and a reserve carries STOP ALL (issue 28 item 2). Real sockets throughout;
the first test runs a real `opentmcl dashboard` process with its default limits."""
from __future__ import annotations

import importlib
import socket
import urllib.parse

import pytest

from .rawhttp import get_json, page_headers, post_json, read_reply, request, start_cli, stop_cli

importlib.import_module("uvicorn")

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


def test_an_idle_connection_gives_its_place_to_a_new_one(limited):
    """Issue 28 item 2 (the rule of docs/dashboard.md "Threat model"): with the four connections of
    the cap open and silent, a fifth is not closed: the connection that has waited longest for a
    request head is closed instead, and the fifth's request is answered."""
    port = limited
    idle = [socket.create_connection(("127.0.0.1", port)) for _ in range(4)]
    assert get_json(port, "/api/modules")[0]["address"] == 1   # a fifth, answered
    assert closed_by_server(idle[0])                              # the oldest gave its place
    for sock in idle:
        sock.close()


def test_a_kept_alive_connection_counts_as_waiting_from_its_last_response(limited):
    """A connection kept alive after a response waits for its next head from then on: a new
    connection takes the place of one that connected after it but has waited longer. Each wait is
    started by a response the test has read, so the order does not hang on when the server
    accepted a connection."""
    port = limited
    early = socket.create_connection(("127.0.0.1", port), timeout=GENEROUS)
    a, b = (socket.create_connection(("127.0.0.1", port), timeout=GENEROUS) for _ in range(2))
    ask = f"GET /api/modules HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode()
    for sock in (a, early, b):                     # a waits from now, then early, then b
        sock.sendall(ask)
        assert read_reply(sock).status == 200      # kept alive: waiting since this response
    late = socket.create_connection(("127.0.0.1", port), timeout=GENEROUS)  # the fourth
    newcomer = socket.create_connection(("127.0.0.1", port))
    assert closed_by_server(a)                    # connected after `early`, waited longer
    early.sendall(ask)                            # well within the 5 s keep-alive
    assert read_reply(early).status == 200        # still open
    for sock in (early, a, b, late, newcomer):
        sock.close()


@pytest.fixture
def busy_cap():
    """A dashboard with 2 connections and a reserve of 2, a long body time-out, and a way to hold
    a connection busy: a POST whose body never completes (a request being answered)."""
    import opentmcl
    from opentmcl.web import start_dashboard

    module = opentmcl.connect("sim://TMCM-6212?clock=real")
    handle = start_dashboard(module, "127.0.0.1", 0, on_stop=module.close, poll=False, max_connections=2,
                             reserve=2, body_timeout=GENEROUS, head_timeout=GENEROUS)
    held: list[socket.socket] = []

    def hold_busy(path: str = "/m/1/api/console") -> socket.socket:
        """A connection whose request is being answered: its body is read (the server's "100
        Continue", RFC 9110 10.1.1, says so) and never completes."""
        head = [f"POST {path} HTTP/1.1", f"Host: 127.0.0.1:{handle.port}", "Content-Length: 100",
                "Expect: 100-continue"]
        head += [f"{k}: {v}" for k, v in page_headers(handle.port).items()]
        sock = socket.create_connection(("127.0.0.1", handle.port), timeout=GENEROUS)
        sock.sendall(("\r\n".join(head) + "\r\n\r\n").encode())
        assert sock.recv(64).startswith(b"HTTP/1.1 100 ")
        sock.sendall(b'{"line": ')
        held.append(sock)
        return sock

    try:
        yield handle.port, hold_busy
    finally:
        for sock in held:
            sock.close()
        handle.stop()


def test_the_reserve_carries_stop_all_only(busy_cap):
    """Issue 28 item 2: STOP ALL gets its own connection slot. Both ordinary connections carry a
    request being answered (nothing to evict); a third connection is a reserve one: any other
    request on it is a 503 with the reason, STOP ALL is answered (program stop 128 and MST on every
    axis, TMCM-6212 manual 3.6.36, 3.6.3)."""
    port, hold_busy = busy_cap
    hold_busy()
    hold_busy()
    r = request(port, "GET", "/api/modules")
    assert r.status == 503 and "only carry STOP ALL" in r.error and "\n" not in r.error
    r = post_json(port, "/api/stop-all", {})
    assert r.status == 200 and r.json()["ok"] and r.json()["modules"][0]["axes_stopped"] == [0, 1, 2, 3, 4, 5]


def test_the_reserve_refuses_a_websocket(busy_cap):
    """A reserve connection does not become a WebSocket (which would hold it for ever): 503."""
    from .rawhttp import ws_upgrade

    port, hold_busy = busy_cap
    hold_busy()
    hold_busy()
    reply = ws_upgrade(port, "/m/1/ws", origin=f"http://127.0.0.1:{port}")
    assert reply.status == 503 and "STOP ALL" in reply.error


def test_idle_connections_in_the_reserve_give_way_to_stop_all(busy_cap):
    """Both ordinary connections busy, the reserve filled by two silent connections: STOP ALL on
    a new connection evicts the reserve connection that waited longest and is answered; only
    when every connection carries a request is a new one closed at once."""
    port, hold_busy = busy_cap
    hold_busy()
    hold_busy()
    idle = [socket.create_connection(("127.0.0.1", port))]
    idle.append(socket.create_connection(("127.0.0.1", port)))
    r = post_json(port, "/api/stop-all", {})
    assert r.status == 200 and r.json()["ok"]
    assert closed_by_server(idle[0])
    hold_busy("/api/stop-all")  # the reserve slot STOP ALL left (a reserve connection carries only that)
    hold_busy("/api/stop-all")  # takes idle[1]'s place
    assert closed_by_server(idle[1])
    refused = socket.create_connection(("127.0.0.1", port))  # every connection is busy now
    assert closed_by_server(refused)
    for sock in (*idle, refused):
        sock.close()


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
    assert get_json(port, "/m/1/api/program")["state"]["mode_name"] == "reset"  # as the download left it
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
