"""Who may talk to the dashboard (docs/dashboard.md, "Threat model"): an ASGI middleware that runs
before any route, so a refused request changes nothing.

1. Host must be a loopback name, the bound address or an allowed name (no DNS rebinding).
2. With a token (LAN use): the cookie, the X-OpenTMCL-Token header or ?token= must carry it;
   a page opened with ?token= gets the cookie (SameSite=Strict) and is redirected without it.
3. Every method but GET/HEAD, and the WebSocket upgrade: an Origin, when sent, must be the
   dashboard's own, and the request must carry ``X-OpenTMCL: 1`` (WebSocket: subprotocol
   ``opentmcl``), which a cross-site form cannot send.
4. A request head (request line and header lines) is at most `HEAD_MAX` bytes, however it
   arrived (uvicorn bounds only a head still incomplete).
5. A body is at most `MAX_BODY` bytes, read before the route runs and never beyond the limit,
   and must be complete within `BODY_TIMEOUT` seconds (a body sent a byte at a time holds no
   connection for ever).

Refusals are 400, 403, 408 or 413 with ``{"error": "<one line>"}`` and a log line.
"""
from __future__ import annotations

import asyncio
import enum
import logging
import secrets
import urllib.parse
from collections.abc import Iterable

from starlette.requests import HTTPConnection
from starlette.responses import JSONResponse, RedirectResponse
from starlette.types import ASGIApp, Message, Receive, Scope, Send

log = logging.getLogger("opentmcl.web")

HEAD_MAX = 16 * 1024         # bytes of a request line and headers (h11's default, made explicit)
MAX_BODY = 1 << 20           # 1 MiB: a full 6144-instruction program source is well below
BODY_TIMEOUT = 30.0          # seconds for the whole body: 1 MiB takes under 10 s even at 1 Mbit/s
HEADER = "x-opentmcl"        # value "1"; a custom header needs a CORS preflight, never granted
TOKEN_HEADER = "x-opentmcl-token"
SUBPROTOCOL = "opentmcl"
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "[::1]")
SAFE_METHODS = ("GET", "HEAD")


class _Gone(enum.Enum):
    GONE = "gone"


GONE = _Gone.GONE  # read_body(): the client disconnected


def host_name(name: str) -> str:
    """`name` as it appears in a Host header: lower case, IPv6 literals in brackets."""
    name = name.strip().lower()
    if ":" in name and not name.startswith("["):
        name = f"[{name}]"
    return name


def split_authority(text: str) -> tuple[str, str] | None:
    """``host[:port]`` -> (host, port or ""); None when malformed."""
    text = text.strip().lower()
    if text.startswith("["):
        end = text.find("]")
        if end < 0:
            return None
        host, rest = text[:end + 1], text[end + 1:]
    else:
        host, sep, port = text.partition(":")
        rest = sep + port
    if rest and not (rest.startswith(":") and rest[1:].isdigit()):
        return None
    if not host or any(c in host for c in "/\\@ ,"):
        return None
    return host, rest[1:]


def new_token() -> str:
    return secrets.token_urlsafe(24)


class Guard:
    """ASGI middleware: see the module docstring. `allowed_hosts` extends the loopback names."""

    def __init__(self, app: ASGIApp, allowed_hosts: Iterable[str] = (), token: str | None = None,
                 max_body: int = MAX_BODY, body_timeout: float = BODY_TIMEOUT) -> None:
        self.app = app
        self.body_timeout = body_timeout
        self.allowed = {host_name(h) for h in (*LOOPBACK_NAMES, *allowed_hosts) if h}
        self.token = token
        self.max_body = max_body

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        size = head_size(scope)
        if size > HEAD_MAX:
            await self.refuse(scope, receive, send, 400, f"request head of {size} bytes, more than {HEAD_MAX}")
            return
        conn = HTTPConnection(scope)
        reason = self.refusal(conn, scope)
        if reason is not None:
            await self.refuse(scope, receive, send, 403, reason)
            return
        if scope["type"] == "http" and self.token and conn.query_params.get("token") and \
                scope["method"] in SAFE_METHODS:
            await self.set_cookie(conn, self.token, scope, receive, send)
            return
        if scope["type"] == "http":
            length = conn.headers.get("content-length", "")
            if length.isdigit() and int(length) > self.max_body:
                await self.refuse(scope, receive, send, 413, self.too_large())
                return
            if scope["method"] not in SAFE_METHODS:
                try:
                    body = await asyncio.wait_for(self.read_body(receive), self.body_timeout)
                except asyncio.TimeoutError:
                    await self.refuse(scope, receive, send, 408,
                                      f"request body not complete within {self.body_timeout:g} s")
                    return
                if body is GONE:
                    return  # the client left before its body was complete: nothing to act on
                if body is None:
                    await self.refuse(scope, receive, send, 413, self.too_large())
                    return
                receive = replay(body, receive)
        await self.app(scope, receive, send)

    def too_large(self) -> str:
        return f"request body larger than {self.max_body} bytes"

    def refusal(self, conn: HTTPConnection, scope: Scope) -> str | None:
        """Why this request is refused, or None."""
        raw_host = conn.headers.get("host")
        if raw_host is None:
            return "missing Host header"
        authority = split_authority(raw_host)
        if authority is None or authority[0] not in self.allowed:
            return (f"Host {_shown(raw_host)} is not allowed (DNS rebinding?); to serve under that name "
                    "start the dashboard with --allow-host NAME")
        if self.token and not self.has_token(conn, self.token):
            return "missing or wrong token: open the dashboard with the ?token=... URL printed at start-up"
        websocket = scope["type"] == "websocket"
        if not websocket and scope["method"] in SAFE_METHODS:
            return None
        origin = conn.headers.get("origin")
        if origin is not None and not same_origin(origin, authority):
            return f"Origin {_shown(origin)} is not this dashboard's (cross-site request)"
        if websocket:
            offered = [p.strip() for p in conn.headers.get("sec-websocket-protocol", "").split(",")]
            if SUBPROTOCOL not in offered:
                return f"missing WebSocket subprotocol {SUBPROTOCOL!r} (the dashboard page sends it)"
        elif conn.headers.get(HEADER) != "1":
            return "missing header X-OpenTMCL: 1 (the dashboard page sends it; scripts must too)"
        return None

    @staticmethod
    def has_token(conn: HTTPConnection, token: str) -> bool:
        given = (conn.headers.get(TOKEN_HEADER) or conn.query_params.get("token")
                 or conn.cookies.get(cookie_name(conn.scope)) or "")
        return secrets.compare_digest(given.encode(), token.encode())

    @staticmethod
    async def set_cookie(conn: HTTPConnection, token: str, scope: Scope, receive: Receive, send: Send) -> None:
        """The page opened with ?token=...: keep the token in a cookie, drop it from the address bar."""
        query = urllib.parse.urlencode([(k, v) for k, v in conn.query_params.multi_items() if k != "token"])
        target = same_site_path(scope.get("root_path", "") + scope["path"]) + (f"?{query}" if query else "")
        response = RedirectResponse(target, status_code=303, headers={"Cache-Control": "no-store"})
        response.set_cookie(cookie_name(scope), token, httponly=True, samesite="strict", path="/")
        await response(scope, receive, send)

    async def read_body(self, receive: Receive) -> bytes | _Gone | None:
        """The whole body, None as soon as it passes the limit (the rest is never read), or GONE."""
        chunks: list[bytes] = []
        size = 0
        while True:
            message = await receive()
            if message["type"] != "http.request":
                return GONE
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > self.max_body:
                return None
            chunks.append(chunk)
            if not message.get("more_body", False):
                return b"".join(chunks)

    async def refuse(self, scope: Scope, receive: Receive, send: Send, status: int, reason: str) -> None:
        client = scope.get("client") or ("?", 0)
        log.warning("refused %s %s from %s: %s", scope.get("method", "WEBSOCKET"), scope["path"],
                    client[0], reason)
        response = JSONResponse({"error": reason}, status_code=status,
                                headers={"Connection": "close"} if status in (408, 413) else None)
        if scope["type"] == "websocket":
            await receive()  # websocket.connect
            if "websocket.http.response" not in scope.get("extensions", {}):
                await send({"type": "websocket.close", "code": 1008, "reason": reason[:120]})
                return
        await response(scope, receive, send)


def same_origin(origin: str, authority: tuple[str, str]) -> bool:
    """Is `origin` (scheme://host[:port]) the dashboard reached at `authority` (from Host)?"""
    scheme, sep, rest = origin.strip().lower().partition("://")
    if not sep or scheme not in ("http", "https"):
        return False
    parsed = split_authority(rest)
    if parsed is None:
        return False
    default = "443" if scheme == "https" else "80"
    return (parsed[0], parsed[1] or default) == (authority[0], authority[1] or default)


def head_size(scope: Scope) -> int:
    """Bytes of the request head as received: request line and ``name: value`` lines, each with
    its CRLF, and the empty line (whitespace h11 dropped around values is not counted)."""
    path = scope.get("raw_path") or scope.get("path", "").encode("latin-1", "replace")
    query = scope.get("query_string", b"")
    line = len(scope.get("method", "GET")) + 1 + len(path) + (1 + len(query) if query else 0) + len(" HTTP/1.1\r\n")
    return line + sum(len(k) + 2 + len(v) + 2 for k, v in scope.get("headers", ())) + 2


def same_site_path(path: str) -> str:
    """`path` as a redirect target that stays on this site: one leading slash (``//host/`` and
    ``/\\host/`` name another site to a browser)."""
    return "/" + path.lstrip("/\\")


def cookie_name(scope: Scope) -> str:
    """One cookie per port: cookies do not tell ports apart, two dashboards on a host must not clash."""
    server = scope.get("server") or (None, 0)
    return f"opentmcl_token_{server[1] or 0}"


def replay(body: bytes, receive: Receive) -> Receive:
    """A receive() that gives `body` once, then what the server sends (a disconnect)."""
    sent = False

    async def again() -> Message:
        nonlocal sent
        if sent:
            return await receive()
        sent = True
        return {"type": "http.request", "body": body, "more_body": False}
    return again


def _shown(text: str) -> str:
    return repr(text if len(text) <= 80 else text[:80] + "...")
