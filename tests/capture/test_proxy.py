"""The proxy relays bytes unchanged in both directions (issue 13 item 1): frames for several addresses,
split frames, garbage and wrong checksums, late command-138 event replies; one-line CLI errors."""
from __future__ import annotations

import socket
import sys
import time

import pytest

from opentmcl import VirtualModule
from opentmcl.capture import read_capture
from opentmcl.capture.proxy import Proxy, ProxySession
from opentmcl.server import Server, TcpServer

from .helpers import Tool, cli, frame

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX")

# TMCM-6212 manual 3.6.8: GGP 66 at addresses 1 and 2; 3.2.1 status 1 for a wrong checksum.
STREAM = [frame(10, 66, 0, address=1), frame(10, 66, 0, address=2), frame(10, 66, 0, address=3),
          frame(6, 4, 0, address=2)[:4], frame(6, 4, 0, address=2)[4:], frame(5, 4, 0, 1234, address=1)[:8] + b"\0",
          frame(6, 4, 0, address=1) + frame(6, 4, 0, address=2)]


def served():
    srv = Server([VirtualModule("TMCM-6212", address=1), VirtualModule("PD28-1021", address=2)])
    tcp = srv.add(TcpServer(srv.bus, "127.0.0.1", 0))
    srv.start()
    return srv, tcp


def talk(address, chunks, expect):
    sock = socket.create_connection(address, timeout=5)
    got = b""
    for chunk in chunks:
        sock.sendall(chunk)
        time.sleep(0.02)
    deadline = time.monotonic() + 5
    while len(got) < expect and time.monotonic() < deadline:
        got += sock.recv(4096)
    sock.close()
    return got


def ask_in_turn(address, frames, expect):
    """Send each frame once the reply of the one before has come; read `expect` bytes in all."""
    sock = socket.create_connection(address, timeout=30)
    got = b""
    try:
        for n, request in enumerate(frames):
            sock.sendall(request)
            while len(got) < 9 * (n + 1):
                got += sock.recv(4096) or b"!"       # "!" ends the wait on EOF, and fails the length check
        while len(got) < expect:
            got += sock.recv(4096) or b"!"
    finally:
        sock.close()
    return got


def test_bytes_through_the_proxy_equal_bytes_straight_from_the_bus(tmp_path):
    direct_srv, direct = served()
    behind_srv, behind = served()
    proxy = Proxy(behind.url, log=str(tmp_path / "c.jsonl"))
    front = proxy.listen(TcpServer(proxy, "127.0.0.1", 0, session=ProxySession))
    proxy.start()
    try:
        expected = talk(direct.address, STREAM, 6 * 9)
        relayed = talk(front.address, STREAM, 6 * 9)
    finally:
        proxy.stop()
        direct_srv.stop()
        behind_srv.stop()
    assert len(expected) == 6 * 9 and relayed == expected
    cap = read_capture(tmp_path / "c.jsonl")
    requests = [r for r in cap.frames if r["kind"] == "request"]
    assert [r["address"] for r in requests] == [1, 2, 3, 2, 1, 1, 2]
    assert [r["checksum_ok"] for r in requests].count(False) == 1
    wrong = next(r for r in cap.frames if r["kind"] == "reply" and r["status"] == 1)
    assert wrong["status_text"] == "Wrong checksum"


def test_late_event_reply_reaches_the_host_and_the_capture(tmp_path):
    """Manual 3.6.35: after 138 and MVP the module sends a second reply (status 128) on arrival."""
    srv, tcp = served()
    proxy = Proxy(tcp.url, log=str(tmp_path / "c.jsonl"))
    front = proxy.listen(TcpServer(proxy, "127.0.0.1", 0, session=ProxySession))
    proxy.start()
    try:
        got = ask_in_turn(front.address, [frame(138, 0, 0, 1), frame(4, 1, 0, 500)], 27)
    finally:
        proxy.stop()
        srv.stop()
    assert got[18 + 2] == 128 and got[18 + 7] == 1
    kinds = [r["kind"] for r in read_capture(tmp_path / "c.jsonl").frames]
    assert kinds == ["request", "reply", "request", "reply", "event"]


@pytest.mark.parametrize("args, message, code", [
    (["--to", "sim://TMCM-6212"], "give --pty", 2),
    (["--to", "nope://x", "--pty"], "unknown URL scheme", 2),
    (["--to", "can://nosuchinterface/x?id=1", "--pty"], "cannot open CAN bus", 3),   # 3: link not opened
    (["--to", "sim://TMCM-6212", "--tcp", "10.1.2.3:5000"], "refusing to bind", 2),
    (["--to", "sim://TMCM-6212", "--pty", "--log", "/nonexistent/dir/c.jsonl"], "cannot write", 2),
    (["--to", "sim://TMCM-9999", "--pty"], "unknown module", 2),
    (["--to", "tcp://127.0.0.1:1", "--pty"], "tcp://127.0.0.1:1", 3),                # (docs/cli.md)
])
def test_cli_errors_are_one_line_exit_2(args, message, code):
    done = cli("proxy", *args, timeout=30)
    assert done.returncode == code and len(done.stderr.splitlines()) == 1 and message in done.stderr


def test_proxy_ends_with_one_line_when_the_module_goes_away(tmp_path):
    with Tool("serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0") as srv:
        proxy = Tool("proxy", "--to", srv.endpoint("tcp"), "--pty", "--log", str(tmp_path / "c.jsonl"))
    deadline = time.monotonic() + 10
    while proxy.proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
    code, out, err = proxy.stop()
    assert code == 3 and "connection closed" in err and len(err.splitlines()) == 1   # 3: link broke (docs/cli.md)
    assert read_capture(tmp_path / "c.jsonl").header["target"] == srv.endpoint("tcp")


def test_can_module_behind_a_serial_host_link(tmp_path):
    """TMCM-6212 manual 3.1/3.2: on CAN the address byte and checksum are left out; the proxy is a
    gateway there: GGP 66 (manual 3.6.8 example) and the version string (136 type 0) come back as
    the serial frames a host expects, and a late 138 event passes too."""
    import uuid

    from opentmcl.server import CanServer

    channel = f"opentmcl-proxy-{uuid.uuid4().hex[:12]}"
    srv = Server([VirtualModule("TMCM-6212", address=1)])
    srv.add(CanServer(srv.bus, "virtual", channel))
    srv.start()
    proxy = Proxy(f"can://virtual/{channel}?id=1&reply_id=2", log=str(tmp_path / "c.jsonl"))
    front = proxy.listen(TcpServer(proxy, "127.0.0.1", 0, session=ProxySession))
    proxy.start()
    try:
        got = talk(front.address, [bytes.fromhex("010A4200000000004D"), frame(136, 0), frame(138, 0, 0, 1),
                                   frame(4, 1, 0, 300)], 5 * 9)
    finally:
        proxy.stop()
        srv.stop()
    assert got[:9] == bytes.fromhex("0201640A0000000172") and got[9:18] == b"\x026212V105"
    assert got[36 + 2] == 128 and got[36 + 7] == 1
    cap = read_capture(tmp_path / "c.jsonl")
    # Order-free (a loaded machine may relay the next request before a reply): counts and pairing.
    assert sorted(r["kind"] for r in cap.frames) == sorted(["request"] * 4 + ["reply"] * 3 + ["version", "event"])
    requests = {r["n"]: r for r in cap.frames if r["kind"] == "request"}
    for r in cap.frames:
        if r["kind"] in ("reply", "version"):
            assert requests[r["request"]]["command"] == (136 if r["kind"] == "version" else r["command"])
    assert cap.identities[0]["module"] == "TMCM-6212"


def test_proxy_tcp_listener_drops_idle_clients_after_idle_timeout():
    """docs/capture.md: the proxy listens exactly as `opentmcl serve` does, so its TCP listener
    drops a client that sends nothing for `--idle-timeout` seconds (docs/endpoints.md) and logs it
    as `opentmcl proxy: ...`. The client is served first (TMCM-6212 manual 3.6.8: GGP 66 answers
    the module address, 1). (Old code: no --idle-timeout option, the proxy did not start.)"""
    with Tool("proxy", "--to", "sim://TMCM-6212", "--tcp", "127.0.0.1:0", "--idle-timeout", "2") as px:
        host, port = px.endpoint("tcp").removeprefix("tcp://").rsplit(":", 1)
        with socket.create_connection((host, int(port)), timeout=5) as sock:
            sock.sendall(frame(10, 66, 0))
            got = b""
            while len(got) < 9:
                got += sock.recv(9 - len(got))
            assert got[2] == 100 and got[4:8] == b"\0\0\0\1"
            sock.settimeout(30)
            assert sock.recv(64) == b""  # closed by the proxy, not by the test's time-out
        code, _, err = px.stop()
    assert code == 0
    assert any(line.startswith("opentmcl proxy: TCP client") and "nothing received for 2 s" in line
               for line in err.splitlines()), err


@pytest.mark.parametrize("seconds", ["-1", "nan", "inf"])
def test_bad_idle_timeout_is_a_one_line_error(seconds):
    """docs/endpoints.md: bad --idle-timeout values are a one-line error, exit code 2."""
    done = cli("proxy", "--to", "sim://TMCM-6212", "--tcp", "127.0.0.1:0", "--idle-timeout", seconds, timeout=30)
    assert done.returncode == 2 and len(done.stderr.splitlines()) == 1
    assert done.stderr.startswith("opentmcl proxy: error: --idle-timeout must be 0 (none) or a positive"), done.stderr


def test_proxy_behind_serve_idle_timeout_names_the_cure():
    """docs/endpoints.md: `opentmcl serve --tcp` drops a client that sends nothing for
    `--idle-timeout` seconds - the proxy is such a client while its host is silent. It ends with
    one line that says how to keep the link (docs/capture.md). (Old code: no hint.)"""
    with Tool("serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--idle-timeout", "1") as srv:
        proxy = Tool("proxy", "--to", srv.endpoint("tcp"), "--pty")
        deadline = time.monotonic() + 30
        while proxy.proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
        code, _, err = proxy.stop()
    assert code == 3 and len(err.splitlines()) == 1
    assert "connection closed" in err and "--idle-timeout 0" in err, err
