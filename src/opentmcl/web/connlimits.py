"""Connection limits of the dashboard's web server (docs/dashboard.md, "Threat model").

uvicorn bounds a request head (h11: `HEAD_MAX` bytes) and closes a kept-alive connection that
stays silent after a response, but it waits for ever on a connection that never completes its
first request head, and it takes any number of connections (each one a file descriptor of the
process that also serves the TCP port, the pty and the EEPROM). `protocol_class` adds both bounds
to uvicorn's h11 protocol:

- a connection whose next request head is not complete within `head_timeout` seconds, while no
  request of it is being answered, is closed (slowloris, a client that connects and sends nothing);
- beyond `max_connections` at once (WebSockets included) a new connection is closed at once.

Both log one warning line, at most one per `LOG_EVERY` seconds (with the count of the others).
"""
from __future__ import annotations

import asyncio
import logging
import time

from uvicorn.protocols.http.h11_impl import H11Protocol

log = logging.getLogger("opentmcl.web")

HEAD_TIMEOUT = 10.0     # seconds for a request head (and between requests of a kept-alive connection)
MAX_CONNECTIONS = 64    # at once; a browser opens at most 6 per host, plus one WebSocket per tab
HEAD_MAX = 16 * 1024    # bytes of a request line and headers (h11's default, made explicit)
KEEP_ALIVE = 5          # seconds uvicorn keeps an idle connection after a response (its default)
LOG_EVERY = 10.0


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


def protocol_class(head_timeout: float = HEAD_TIMEOUT, max_connections: int = MAX_CONNECTIONS) -> type[H11Protocol]:
    """uvicorn's h11 protocol with the two bounds above (a class per server: the limits differ)."""
    if not head_timeout > 0 or max_connections < 1:
        raise ValueError("head_timeout must be > 0 and max_connections >= 1")
    too_many, too_slow = _RareLog(), _RareLog()

    class LimitedH11Protocol(H11Protocol):
        _head_timer: asyncio.TimerHandle | None
        _last_scope: object  # the request head seen at the last look, compared by identity

        # uvicorn's H11Protocol already narrows BaseProtocol's BaseTransport to Transport; same here
        def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
            super().connection_made(transport)
            self._head_timer = None
            if len(self.connections) > max_connections:
                too_many.warn("dashboard: connection from %s closed: %d connections open, the maximum",
                              _peer(self.client), max_connections)
                transport.close()
                return
            self._last_scope = None
            self._head_timer = self.loop.call_later(head_timeout, self._check_head)

        def connection_lost(self, exc: Exception | None) -> None:
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


def _peer(client: tuple[str, int] | None) -> str:
    return f"{client[0]}:{client[1]}" if client else "?"
