"""A host `Transport` onto a running server's `ModuleBus`, so the dashboard of
`opentmcl serve --web` talks to the served modules through the host library like any client.

Requests are offered to the bus without a channel, so the bus keeps routing the modules'
unsolicited replies (command 138, TMCM-6212 manual 3.6.35) to the TCP/pty/CAN client that
asked for them: the dashboard never steals another host's events (docs/assumptions.md). The
transport is a link of its own all the same (`link=`): a program download belongs to the link
that opened it (server/downloads.py), so the dashboard's polls during another host's download
are executed, not stored, and its own download is not disturbed by the other hosts.

The bus answers while `send` runs, so a reply that is not there when `send` returns never comes:
reading it fails at once instead of after the time-out (a scan of an empty address, a module that
stays silent), and nothing holds the dashboard's link waiting for it (issue 28: a stop waited up
to a scan's time-out per address for such a read).
"""
from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING

from ..host.errors import TmclConnectionError, TmclTimeout
from ..host.transport import Transport

if TYPE_CHECKING:
    from ..server.bus import ModuleBus


class BusTransport(Transport):
    frame_format = "serial"

    def __init__(self, bus: ModuleBus) -> None:
        self.bus = bus
        self._rx = bytearray()
        self._cond = threading.Condition()
        self._closed = False
        self._answered = False  # a send's replies are all in `_rx`: nothing more is coming for it

    def local_module(self, address: int):
        """The served module at `address` (the dashboard runs in the server's process)."""
        return next((m for m in self.bus.modules if m.accepts_address(address)), None)

    def send(self, data: bytes) -> None:
        if self._closed:
            raise TmclConnectionError("dashboard bus link is closed")
        replies = self.bus.request(bytes(data), None, link=self)
        with self._cond:
            for _vm, reply in replies:
                self._rx += reply
            self._answered = True
            self._cond.notify_all()

    def recv(self, n: int, timeout: float) -> bytes:
        deadline = time.monotonic() + max(0.0, timeout)
        with self._cond:
            if len(self._rx) < n and self._answered:  # the bus answered the request with less
                self._answered = False
                raise TmclTimeout(f"no reply: the served modules answered {len(self._rx)} of {n} bytes")
            while len(self._rx) < n:
                left = deadline - time.monotonic()
                if left <= 0 or self._closed:
                    raise TmclTimeout(f"no reply within {timeout:g} s ({len(self._rx)} of {n} bytes received)")
                self._cond.wait(min(left, 0.05))
            out = bytes(self._rx[:n])
            del self._rx[:n]
            return out

    def reset_input(self) -> None:
        with self._cond:
            self._rx.clear()
            self._answered = False

    def close(self) -> None:
        """No more requests; a download this link opened has no owner from now on."""
        if not self._closed:
            self._closed = True
            self.bus.forget(self)
