"""HTTP over a plain socket, for requests a polite client will not send: a forged Host, a foreign
Origin, a form-encoded body, a Content-Length the body never reaches, a raw WebSocket upgrade."""
from __future__ import annotations

import http.client
import json
import os
import signal
import socket
import subprocess
import sys
from dataclasses import dataclass

import pytest

WS_KEY = "dGhlIHNhbXBsZSBub25jZQ=="  # RFC 6455 section 1.3's example key


@dataclass
class Reply:
    status: int
    headers: http.client.HTTPMessage
    body: bytes

    def json(self):
        return json.loads(self.body)

    @property
    def error(self) -> str:
        return self.json()["error"]


def send_raw(port: int, data: bytes, *, timeout: float = 10.0) -> Reply:
    """Send `data` as it is on a new connection to 127.0.0.1:`port`; the response."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as sock:
        sock.sendall(data)
        return read_reply(sock, data.split(b" ", 1)[0].decode("latin-1"))


def read_reply(sock: socket.socket, method: str = "GET") -> Reply:
    response = http.client.HTTPResponse(sock, method=method)
    response.begin()
    body = b"" if response.status == 101 else response.read()
    return Reply(response.status, response.headers, body)


def request(port: int, method: str, path: str, *, host: str | None = None, headers: dict | None = None,
            body: bytes = b"", timeout: float = 10.0) -> Reply:
    """One request with exactly these headers (Host is 127.0.0.1:`port` unless `host` is given;
    host="" sends none)."""
    lines = [f"{method} {path} HTTP/1.1"]
    host = f"127.0.0.1:{port}" if host is None else host
    if host:
        lines.append(f"Host: {host}")
    for k, v in (headers or {}).items():
        lines.append(f"{k}: {v}")
    if body or method not in ("GET", "HEAD"):
        lines.append(f"Content-Length: {len(body)}")
    lines.append("Connection: close")
    return send_raw(port, ("\r\n".join(lines) + "\r\n\r\n").encode("latin-1") + body, timeout=timeout)


def page_headers(port: int) -> dict:
    """What the dashboard's own page sends with a POST (app.js)."""
    return {"Origin": f"http://127.0.0.1:{port}", "X-OpenTMCL": "1", "Content-Type": "application/json"}


def post_json(port: int, path: str, data, **kw) -> Reply:
    headers = {**page_headers(port), **kw.pop("headers", {})}
    return request(port, "POST", path, headers=headers, body=json.dumps(data).encode(), **kw)


def get_json(port: int, path: str, **kw):
    r = request(port, "GET", path, **kw)
    assert r.status == 200, (path, r.status, r.body[:200])
    return r.json()


def target(port: int, axis: int = 0, **kw) -> int:
    """Axis parameter 0, target position (TMCM-6212 manual 4.1), read now with GAP."""
    params = get_json(port, f"/m/1/api/params/axis/{axis}", **kw)["params"]
    return next(p["value"] for p in params if p["number"] == 0)


def ws_upgrade(port: int, path: str, *, host: str | None = None, origin: str | None = None,
               protocol: str | None = "opentmcl", extra: dict | None = None) -> Reply:
    """A WebSocket opening handshake (RFC 6455 4.1) as a browser sends it; the server's answer."""
    headers = {"Upgrade": "websocket", "Connection": "Upgrade", "Sec-WebSocket-Key": WS_KEY,
               "Sec-WebSocket-Version": "13"}
    if origin is not None:
        headers["Origin"] = origin
    if protocol is not None:
        headers["Sec-WebSocket-Protocol"] = protocol
    headers.update(extra or {})
    lines = [f"GET {path} HTTP/1.1", f"Host: {host if host is not None else f'127.0.0.1:{port}'}"]
    lines += [f"{k}: {v}" for k, v in headers.items()]
    return send_raw(port, ("\r\n".join(lines) + "\r\n\r\n").encode("latin-1"))


def start_cli(args: list[str], marker: str):
    """`python -m opentmcl ARGS` until a line with `marker` and a URL: (process, URL, lines so far)."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "opentmcl", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, env=env)
    lines = []
    for line in proc.stdout:
        lines.append(line)
        if marker in line and "http" in line:
            url = "http" + line.split("http", 1)[1].split()[0]
            return proc, url, lines
    proc.wait()
    pytest.fail(f"no dashboard URL printed: {''.join(lines)}")


def stop_cli(proc) -> str:
    """SIGTERM, wait for the exit, and the output after the lines `start_cli` read (also what its
    line iteration had buffered, which communicate(timeout=...) would skip)."""
    proc.send_signal(signal.SIGTERM)
    proc.wait(timeout=30)
    with proc.stdout:
        return proc.stdout.read()
