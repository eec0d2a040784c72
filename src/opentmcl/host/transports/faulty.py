"""An in-process link with link faults (``sim://NAME?faults=FILE``, docs/faults.md "Link faults").

The same decisions as a served link (opentmcl.faults `LinkFaults`), applied to frames handed to
in-process modules, in the transport's time (virtual by default): a request dropped never reaches
the module; a request with a byte flipped is answered with status 1 ("wrong checksum", manual
3.2.1); a request cut into pieces reaches the module only when no gap between them is longer than
the frame gap (`FRAME_GAP`, the rule of a served module's framer, server/framer.py); a reply
dropped never arrives; a garbled one arrives with a byte flipped; a delayed one, and everything
behind it, arrives later; a reply cut into pieces arrives piece by piece; while the link is down
nothing passes. Replies and events keep their order, as on a serial line.
"""
from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable

from ...faults import Fate, LinkFaults, corrupt, cut, survives
from ...protocol.frame import FRAME_GAP, FRAME_LEN
from ..errors import TmclTimeout
from ..transport import DEBUG, log, log_frame
from .inprocess import Clock, InProcessTransport, M


def request_fields(frame: bytes) -> tuple[int, int, int, int] | None:
    """(command, type, motor, value) of a 9-byte request frame, else None."""
    if len(frame) != FRAME_LEN:
        return None
    return frame[1], frame[2], frame[3], int.from_bytes(frame[4:8], "big", signed=True)


class FaultyTransport(InProcessTransport[M]):
    """`InProcessTransport` whose link has faults (`link`: its `LinkFaults`)."""

    window = 1  # a lossy link: a batch goes one request at a time, as on a serial line

    def __init__(self, modules: M | Iterable[M], link: LinkFaults, clock: str | Clock = "virtual",
                 frame_gap: float = FRAME_GAP) -> None:
        super().__init__(modules, clock)
        self.link = link
        self.frame_gap = frame_gap
        self.on_the_way: deque[tuple[float, bytes]] = deque()
        """Bytes sent by the modules that have not arrived yet: (arrival time, bytes), in order."""
        self.last_due = -math.inf

    def next_arrival_in(self) -> float | None:
        if not self.on_the_way:
            return None
        return max(0.0, self.on_the_way[0][0] - self.monotonic())

    # --- sending: the fate of each request -----------------------------------------------------
    def send(self, data: bytes) -> None:
        with self.lock:
            self._check_open()
            if self.clock.syncs:
                self.clock.sync(self)
            self._collect()
            if log.isEnabledFor(DEBUG):
                log_frame("->", data, self.frame_format)
            frame = bytes(data)
            t = self.monotonic()
            fate = self.link.request(request_fields(frame), t)
            if not fate.drop_request:
                self._deliver_with(frame, fate, t)
            self._collect()

    def _deliver_with(self, frame: bytes, fate: Fate, t: float) -> None:
        if fate.corrupt_request is not None:
            frame = corrupt(frame, fate.corrupt_request)
        late = 0.0
        if fate.split_request is not None:
            if not survives(fate.split_request, self.frame_gap):
                return  # the module dropped the partial frame after a gap longer than the frame gap
            late = sum(gap for _length, gap in fate.split_request)
        reply = b"".join(m.handle(frame) for m in self.modules)
        if reply and not fate.drop_reply:
            if fate.corrupt_reply is not None:
                reply = corrupt(reply, fate.corrupt_reply)
            due = t + late + fate.delay
            for chunk, gap in cut(reply, fate.split_reply) if fate.split_reply is not None else [(reply, 0.0)]:
                due += gap
                self._put(chunk, due)
        self._collect(t)  # events the request raised follow its reply

    def _put(self, data: bytes, due: float) -> None:
        """`data` on its way, arriving at `due` or behind what is on the way already (lost if the
        link is down then)."""
        due = max(due, self.last_due)
        if self.link.down(due):
            return
        self.last_due = due
        self.on_the_way.append((due, data))

    def _collect(self, t: float | None = None) -> None:
        """The modules' events on their way (at `t`, default now); what is due arrives."""
        now = self.monotonic() if t is None else t
        for m in self.modules:
            for event in m.drain_events():
                self._put(event, now)
        due = self.monotonic()
        way = self.on_the_way
        while way and way[0][0] <= due:
            self._rx += way.popleft()[1]

    # --- time and receiving ----------------------------------------------------------------------
    def advance(self, seconds: float) -> None:
        with self.lock:
            self._check_open()
            for m in self.modules:
                m.advance(seconds)
            self.elapsed += seconds
            self._collect()

    def recv(self, n: int, timeout: float) -> bytes:
        with self.lock:
            self._check_open()
            self._collect()
            rx = self._rx
            if len(rx) < n:
                self.clock.wait(self, lambda: len(rx) >= n, timeout)
            if len(rx) < n:
                raise TmclTimeout(f"no reply within {timeout:g} s ({len(rx)} of {n} bytes received)")
            out = bytes(rx[:n])
            del rx[:n]
            if log.isEnabledFor(DEBUG):
                log_frame("<-", out, self.frame_format)
            return out
