"""Connection limits of the dashboard's web server (docs/dashboard.md, "Threat model").

uvicorn bounds a request head while it is incomplete (h11: `HEAD_MAX` bytes) and closes a
kept-alive connection that stays silent after a response, but it waits for ever on a connection
that never completes its first request head, and it takes any number of connections (each one a
file descriptor of the process that also serves the TCP port, the pty and the EEPROM).
`protocol_class` adds these bounds to uvicorn's h11 protocol:

- a connection whose next request head is not complete within `head_timeout` seconds, while no
  request of it is being answered, is closed (slowloris, a client that connects and sends nothing);
- at most `max_connections` ordinary connections at once (WebSockets included), plus `reserve`
  connections that may carry only STOP ALL (``POST /api/stop-all``; anything else is answered
  503 and the connection closed);
- a new connection beyond the cap takes the place of the connection that has waited longest for
  a request head (its first, or the next one after a response) without a request being answered:
  an ordinary one, else a reserve one, which is closed. Only when every connection carries a
  request being answered (or is a WebSocket) is the new one closed at once.

So idle or slow connections can never keep STOP ALL out: they are evicted, oldest first, and
connections busy with requests leave the reserve to STOP ALL. Each refusal logs one warning line,
at most one per `LOG_EVERY` seconds (with the count of the others).
"""
from __future__ import annotations

import asyncio
import json
import logging
import time

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

from .guard import HEAD_MAX

log = logging.getLogger("opentmcl.web")

HEAD_TIMEOUT = 10.0     # seconds for a request head (and between requests of a kept-alive connection)
MAX_CONNECTIONS = 64    # at once; a browser opens at most 6 per host, plus one WebSocket per tab
RESERVE = 8             # more connections, for STOP ALL only
STOP_ALL_PATH = "/api/stop-all"  # the one request a reserve connection may carry (POST)
KEEP_ALIVE = 5          # seconds uvicorn keeps an idle connection after a response (its default)
LOG_EVERY = 10.0

__all__ = ["HEAD_MAX", "HEAD_TIMEOUT", "KEEP_ALIVE", "MAX_CONNECTIONS", "RESERVE", "STOP_ALL_PATH",
           "protocol_class"]


class _RareLog:
    """A warning at most every LOG_EVERY seconds, counting the ones left out."""

    def __init__(self) -> None:
        self.last = -LOG_EVERY
        self.quiet = 0

    def warn(self, text: str, *args: object) -> None:
        now = time.monotonic()
        if now - self.last < LOG_EVERY:
            self.quiet += 1
            return
        more = f" ({self.quiet} more since the last line)" if self.quiet else ""
        log.warning(text + more, *args)
        self.last, self.quiet = now, 0


def _closing(protocol: object) -> bool:
    transport = getattr(protocol, "transport", None)
    return transport is None or transport.is_closing()


def protocol_class(head_timeout: float = HEAD_TIMEOUT, max_connections: int = MAX_CONNECTIONS,
                   reserve: int = RESERVE) -> type[H11Protocol]:
    """uvicorn's h11 protocol with the bounds above (a class per server: the limits differ)."""
    if not head_timeout > 0 or max_connections < 1 or reserve < 0:
        raise ValueError("head_timeout must be > 0, max_connections >= 1 and reserve >= 0")
    too_many, too_slow, evicted, refused = _RareLog(), _RareLog(), _RareLog(), _RareLog()
    live: dict[LimitedH11Protocol, None] = {}     # h11 connections of this server, oldest first
    reserved: set[LimitedH11Protocol] = set()     # those that may carry only STOP ALL

    def longest_waiting(among_reserved: bool) -> LimitedH11Protocol | None:
        found = [c for c in live if (c in reserved) == among_reserved and c.waiting_for_head()]
        return min(found, key=lambda c: c.waiting_since, default=None)

    class LimitedH11Protocol(H11Protocol):
        _head_timer: asyncio.TimerHandle | None
        _last_scope: object  # the request head seen at the last look, compared by identity
        waiting_since: float

        # uvicorn's H11Protocol already narrows BaseProtocol's BaseTransport to Transport; same here
        def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
            super().connection_made(transport)
            self._head_timer = None
            self._last_scope = None
            self.waiting_since = time.monotonic()
            if not self._take_slot():
                too_many.warn("dashboard: connection from %s closed: %d connections open, each with a "
                              "request being answered", _peer(self.client), max_connections + reserve)
                transport.close()
                return
            live[self] = None
            self._head_timer = self.loop.call_later(head_timeout, self._check_head)

        def _take_slot(self) -> bool:
            """An ordinary slot, an idle ordinary connection's, a reserve slot or an idle reserve
            connection's (docstring of the module); False when none is left."""
            open_now = sum(1 for c in self.connections if c is not self and not _closing(c))
            in_reserve = sum(1 for c in reserved if not _closing(c))
            if open_now - in_reserve < max_connections:
                return True
            for among_reserved in (False, True):
                if among_reserved and in_reserve < reserve:
                    self._reserve_only()
                    return True
                victim = longest_waiting(among_reserved)
                if victim is not None:
                    evicted.warn("dashboard: connection from %s closed after %.1f s without a request: "
                                 "its place went to a new connection (%d open, the maximum)",
                                 _peer(victim.client), time.monotonic() - victim.waiting_since,
                                 max_connections + (reserve if among_reserved else 0))
                    victim.transport.close()
                    if among_reserved:
                        self._reserve_only()
                    return True
            return False

        def _reserve_only(self) -> None:
            reserved.add(self)
            self.app = _stop_all_only(self.app, refused)

        def waiting_for_head(self) -> bool:
            """Open, not a WebSocket, and no request of it is being answered."""
            return (not _closing(self) and self.transport.get_protocol() is self
                    and (self.cycle is None or self.cycle.response_complete))

        def on_response_complete(self) -> None:
            self.waiting_since = time.monotonic()
            super().on_response_complete()

        def handle_websocket_upgrade(self, event: h11.Request) -> None:
            live.pop(self, None)
            if self in reserved:  # a reserve connection carries STOP ALL, nothing else
                refused.warn("dashboard: WebSocket from %s refused: at the connection limit", _peer(self.client))
                self._answer_503(REFUSAL)
                return
            super().handle_websocket_upgrade(event)

        def _answer_503(self, text: str) -> None:
            headers = [(b"content-type", b"application/json"), (b"connection", b"close")]
            body = json.dumps({"error": text}).encode()
            for event in (h11.Response(status_code=503, headers=headers, reason=b"Service Unavailable"),
                          h11.Data(data=body), h11.EndOfMessage()):
                self.transport.write(self.conn.send(event) or b"")
            self.transport.close()

        def connection_lost(self, exc: Exception | None) -> None:
            live.pop(self, None)
            reserved.discard(self)
            if self._head_timer is not None:
                self._head_timer.cancel()
                self._head_timer = None
            super().connection_lost(exc)

        def _check_head(self) -> None:
            self._head_timer = None
            if self.transport.is_closing() or self.transport.get_protocol() is not self:
                return  # closed, or upgraded to a WebSocket (which has its own ping timeout)
            answering = self.cycle is not None and not self.cycle.response_complete
            if answering or self.scope is not self._last_scope:
                self._last_scope = self.scope  # a new request head arrived since the last look
                self._head_timer = self.loop.call_later(head_timeout, self._check_head)
                return
            too_slow.warn("dashboard: connection from %s closed: no complete request within %g s",
                          _peer(self.client), head_timeout)
            self.transport.close()

    return LimitedH11Protocol


REFUSAL = ("the dashboard is at its connection limit: this connection may only carry STOP ALL "
           f"(POST {STOP_ALL_PATH})")


def _stop_all_only(app, refused: _RareLog):
    """`app` for a reserve connection: POST /api/stop-all goes on, anything else is a 503."""
    from starlette.responses import JSONResponse

    async def reserve_app(scope, receive, send) -> None:
        if scope["type"] == "http" and scope["method"] == "POST" and scope["path"] == STOP_ALL_PATH:
            await app(scope, receive, send)
            return
        if scope["type"] == "http":
            refused.warn("dashboard: %s %s from %s refused: at the connection limit", scope["method"],
                         scope["path"][:80], _peer(scope.get("client")))
            response = JSONResponse({"error": REFUSAL}, status_code=503, headers={"Connection": "close"})
            await response(scope, receive, send)
            return
        await app(scope, receive, send)
    return reserve_app


def _peer(client: tuple[str, int] | None) -> str:
    return f"{client[0]}:{client[1]}" if client else "?"
