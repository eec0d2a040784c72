"""Link faults on a served link (docs/faults.md "Link faults"): the fate of each request frame, as
`opentmcl.faults.LinkFaults` decides it, applied to the bytes of a pty, a TCP client, an RS-485
bus or a CAN bus.

On a serial-framed link (`FaultyLine`) the received bytes are cut into 9-byte frames by counting,
with the frame-gap rule of the module's own framer (a partial frame silent for longer than the
gap is dropped, server/framer.py); each frame then reaches the stream (and the module's framer)
whole, with a byte flipped (the module answers status 1), in pieces with gaps (which its framer
takes as they come: a gap longer than its frame gap loses the frame), or not at all. The reply is
written, written with a byte flipped, held back, written in pieces, or not at all. Waiting is done
by the link's own thread without the bus lock (docs/architecture.md "Real time"). Lines in ASCII
mode pass unchanged.

On CAN a frame is one unit: a frame with a flipped bit fails its CRC and is lost, and a frame
cannot be cut (docs/assumptions.md).
"""
from __future__ import annotations

from collections.abc import Callable

from ..faults import LINK_KINDS, Fate, LinkFaults, corrupt, cut
from ..protocol.frame import FRAME_LEN
from .stream import BINARY, in_ascii_mode

Feed = Callable[[bytes, float], list]
"""The session's stream: bytes received at a line time -> the modules' outputs (vm, data, kind)."""
Write = Callable[..., None]
"""`SerialSession.send_reply(vm, data, pause=...)`."""


CAN_KINDS = tuple(kind for kind in LINK_KINDS if kind not in ("split_request", "split_reply"))
"""The link faults of CAN: a frame is one unit, never cut (docs/assumptions.md)."""


def link_faults(bus, scope: str) -> LinkFaults | None:
    """The link faults a new link of `bus` gets (`ModuleBus.faults`, a FaultBoard), or None."""
    board = getattr(bus, "faults", None)
    return None if board is None else board.link(scope, CAN_KINDS if scope == "can" else None)


def fields_of(frame: bytes) -> tuple[int, int, int, int] | None:
    if len(frame) != FRAME_LEN:
        return None
    return frame[1], frame[2], frame[3], int.from_bytes(frame[4:8], "big", signed=True)


class FaultyLine:
    """The link faults of one serial-framed link, between its bytes and its `SerialStream`."""

    def __init__(self, faults: LinkFaults, bus, feed: Feed, write: Write, sleep: Callable[[float], None],
                 gap: float) -> None:
        self.faults = faults
        self.bus = bus
        self.feed = feed
        self.write = write
        self.sleep = sleep
        self.gap = gap
        self.partial = b""
        self.last = 0.0

    def now(self) -> float:
        """The faults' clock (seconds since the server started)."""
        return self.faults.log.clock()

    def down(self) -> bool:
        return self.faults.down(self.now())

    def receive(self, data: bytes, line_now: float) -> float:
        """Bytes read at `line_now` (the session's line clock): each frame meets its fate. Returns
        the seconds spent waiting (gaps, delays), which are no business of the line clock."""
        if any(in_ascii_mode(vm) for vm in self.bus.modules):
            self.partial = b""
            for vm, out, kind in self.feed(data, line_now):
                self.write(vm, out, pause=kind == BINARY)
            return 0.0
        if self.partial and line_now - self.last > self.gap:
            self.partial = b""   # the module's framer drops it too
        buf, self.last = self.partial + data, line_now
        whole = len(buf) - len(buf) % FRAME_LEN
        self.partial = buf[whole:]
        slept = 0.0
        for pos in range(0, whole, FRAME_LEN):
            frame = buf[pos:pos + FRAME_LEN]
            fate = self.faults.request(fields_of(frame), self.now())
            if not fate.drop_request:
                slept += self._deliver(frame, fate, line_now + slept)
        return slept

    def _deliver(self, frame: bytes, fate: Fate, line_now: float) -> float:
        if fate.corrupt_request is not None:
            frame = corrupt(frame, fate.corrupt_request)
        slept, outputs = 0.0, []
        for chunk, gap in cut(frame, fate.split_request) if fate.split_request is not None else [(frame, 0.0)]:
            if gap:
                self.sleep(gap)
                slept += gap
            outputs += self.feed(chunk, line_now + slept)
        for vm, out, kind in outputs:
            slept += self._reply(vm, out, kind, fate)
        return slept

    def _reply(self, vm, out: bytes, kind: str, fate: Fate) -> float:
        if kind != BINARY:
            self.write(vm, out, pause=False)
            return 0.0
        if fate.drop_reply:
            return 0.0
        slept = 0.0
        if fate.delay > 0:
            self.sleep(fate.delay)
            slept += fate.delay
        if self.down():
            return slept
        if fate.corrupt_reply is not None:
            out = corrupt(out, fate.corrupt_reply)
        pieces = cut(out, fate.split_reply) if fate.split_reply is not None else [(out, 0.0)]
        for i, (chunk, gap) in enumerate(pieces):
            if gap:
                self.sleep(gap)
                slept += gap
            self.write(vm, chunk, pause=i == 0)
        return slept


def can_fate(faults: LinkFaults, data: bytes) -> Fate:
    """The fate of a CAN request (command, type, motor, value[, checksum])."""
    fields = (data[0], data[1], data[2], int.from_bytes(data[3:7], "big", signed=True)) if len(data) >= 7 else None
    return faults.request(fields, faults.log.clock())


def can_request_lost(fate: Fate) -> bool:
    """A CAN request that never reaches the module: dropped, or a bit flipped (its CRC fails)."""
    return fate.drop_request or fate.corrupt_request is not None


def can_reply_passes(fate: Fate, faults: LinkFaults | None, sleep: Callable[[float], object]) -> bool:
    """Hold a CAN reply back as its fate says; False when it is lost (dropped, a bit flipped, or
    the link down when it would go out)."""
    if fate.drop_reply or fate.corrupt_reply is not None:
        return False
    if fate.delay > 0:
        sleep(fate.delay)
    return faults is None or not faults.down(faults.log.clock())
