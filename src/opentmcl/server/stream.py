"""One serial byte stream, read by every module on the bus in its own mode.

On an RS-232/RS-485 line every module's UART sees every byte, and each module
reads them in its own mode:

- binary mode: 9-byte frames found by counting (TMCM-6212 manual 3.1), with a
  partial frame dropped after an inter-byte gap (`SerialFramer`);
- ASCII mode (PD28-1021 manual 3.4, PD86-1180 manual 4.5): entered with
  binary command 139 or at start-up with GP67 bit 0; text lines such as
  ``AGAP 1, 0<CR>``, echoed per GP67 bits 4/5 and answered ``BA 100 -5000``
  by the module whose address character starts the line; left with ``BIN``,
  after which the following bytes are binary frames again.

`SerialStream` therefore keeps one framer per module and walks the received
bytes for each module separately: a 139 frame switches that module to ASCII
for the rest of the chunk, a ``BIN`` line switches it back (the framer starts
afresh at the byte after the line). The outputs of all modules are returned in
stream order (by the byte position that produced them). With every module in
binary mode this is the same as one framer whose frames are offered to all.

The class is pure apart from the bus: the caller passes the arrival time.
"""
from __future__ import annotations

import logging
from logging import DEBUG
from typing import NamedTuple

from ..protocol.frame import FRAME_LEN
from ..protocol.opcodes import keeps_addressing
from .bus import urgency
from .framer import DEFAULT_GAP, SerialFramer

log = logging.getLogger("opentmcl.server.stream")  # every frame at DEBUG (docs/host.md "Logging")

BINARY = "binary"
ASCII = "ascii"


def in_ascii_mode(vm) -> bool:
    """Is `vm` reading its serial line as ASCII text (command 139 / GP67 bit 0)?"""
    return getattr(vm, "ascii_mode", False) is True


class Output(NamedTuple):
    """Bytes a module sends back: a binary reply frame, or ASCII echo and reply text.
    (`SerialStream.feed` may return plain (vm, data, kind) tuples on its fast path.)"""

    vm: object
    data: bytes
    kind: str  # BINARY or ASCII


def _name(vm) -> str:
    return getattr(getattr(vm, "profile", None), "name", type(vm).__name__)


def _log_exchange(vm, frame: bytes, reply: bytes) -> None:
    """A request one module read and its reply (if it gave one), as TMCL text plus hex."""
    from ..host.transport import frame_text

    log.debug("%s <- %s", _name(vm), frame_text(frame, request=True))
    if reply:
        log.debug("%s -> %s", _name(vm), frame_text(reply, request=False))


def _log_frames(frame: bytes, outputs: list) -> None:
    """A request every module of the bus read at once (the fast path) and the replies to it."""
    from ..host.transport import frame_text

    log.debug("bus <- %s", frame_text(frame, request=True))
    for vm, data, _kind in outputs:
        log.debug("%s -> %s", _name(vm), frame_text(data, request=False))


class SerialStream:
    """Splits a serial byte stream into frames and ASCII lines for the modules of `bus`."""

    def __init__(self, bus, gap: float = DEFAULT_GAP) -> None:
        self.bus = bus
        self.gap = gap
        self._framers = [SerialFramer(gap) for _ in bus.modules]
        self._partial = False  # does any framer hold part of a frame?
        self.frames = 0
        """Binary frames completed so far (counted once, whatever the number of modules)."""

    @property
    def framer(self) -> SerialFramer:
        """The first module's framer (for diagnostics: pending, dropped)."""
        return self._framers[0]

    def reset(self) -> None:
        for framer in self._framers:
            framer.reset()
        self._partial = False

    def feed(self, data: bytes, now: float, channel=None) -> list:
        """Bytes received at time `now` -> what the modules send back, in stream order:
        a list of `Output` (or plain (vm, data, kind) tuples).

        A module that raises (a firmware bug: bad input is answered with a
        status code) is logged; its frame or text gets no reply and the stream
        lives on."""
        bus = self.bus
        if data.__class__ is not bytes:
            data = bytes(data)
        size = len(data)
        if size >= FRAME_LEN and not self._partial:
            # The common case, kept lean: whole frames while every module is between frames and
            # in binary mode (one frame, or several sent at once by a pipelining host). A stop
            # (MST, 128, 131) takes the bus ahead of the requests waiting (docs/architecture.md).
            lock = bus.lock
            lock.acquire(urgency(data))
            try:
                for vm in bus.modules:
                    if getattr(vm, "ascii_mode", False) is True:
                        break
                else:
                    bus.sync()
                    if size == FRAME_LEN:
                        self.frames += 1
                        outputs = bus.serial_frames(data, channel)
                        if log.isEnabledFor(DEBUG):
                            _log_frames(data, outputs)
                        return outputs
                    return self._feed_frames(data, now, channel)
            finally:
                lock.release()
        return self._feed_each(data, now, channel)

    def _feed_frames(self, data: bytes, now: float, channel) -> list:
        """Several frames (and maybe the start of another) while every module is in binary mode:
        each frame to the bus in turn, in order; once a frame may have switched a module to ASCII
        (command 139, or 137 with GP67 bit 0 stored), the rest goes the general way."""
        bus = self.bus
        outputs: list = []
        pos, size = 0, len(data)
        lock = bus.lock
        closable = channel if hasattr(channel, "closed") else None
        while size - pos >= FRAME_LEN:
            if pos:  # between two frames (`_between_frames`, inlined: this loop is hot)
                if lock.stops_waiting:
                    lock.yield_to_stops()
                if closable is not None and closable.closed:
                    return outputs
            frame = data[pos:pos + FRAME_LEN]
            pos += FRAME_LEN
            self.frames += 1
            out = bus.serial_frames(frame, channel)
            if log.isEnabledFor(DEBUG):
                _log_frames(frame, out)
            outputs += out
            if not keeps_addressing(frame[1], frame[3]) and any(in_ascii_mode(vm) for vm in bus.modules):
                break
        if pos < size:
            outputs += self._feed_each(data[pos:], now, channel)
        return outputs

    def _between_frames(self, channel) -> bool:
        """Between two frames of one read (a pipelining host may send hundreds, each maybe costly):
        a stop that waits for the bus goes first (docs/architecture.md "Real time"); False when
        the link is closing (the server stops): the rest of the read is dropped."""
        lock = self.bus.lock
        if lock.stops_waiting:
            lock.yield_to_stops()
        return not getattr(channel, "closed", False)

    def _feed_each(self, data: bytes, now: float, channel) -> list[Output]:
        """The general case: every module reads the bytes in its own mode."""
        bus = self.bus
        found: list[tuple[int, int, Output]] = []
        frames = 0
        with bus.lock.hold(self._urgency(data)):
            bus.sync()
            for index, vm in enumerate(bus.modules):
                frames = max(frames, self._feed_module(index, vm, data, now, channel, found))
            self._partial = any(framer.pending for framer in self._framers)
        self.frames += frames
        if len(found) > 1:
            found.sort(key=lambda item: (item[0], item[1]))
        return [item[2] for item in found]

    def _urgency(self, data: bytes) -> int:
        """The bus lock's class for `data` on the general path: urgent when a stop command is at a
        frame position, counted from the partial frame the (first) framer holds."""
        return urgency(self._framers[0].partial + data if self._partial else data)

    def _frame(self, vm, frame: bytes, channel) -> bytes:
        try:
            reply = self.bus.serial_frame(vm, frame, channel)
        except Exception:
            log.exception("module failed on frame %s", frame.hex(" "))
            return b""
        if log.isEnabledFor(DEBUG):
            _log_exchange(vm, frame, reply)
        return reply

    def _feed_module(self, index: int, vm, data: bytes, now: float, channel, found: list) -> int:
        framer = self._framers[index]
        framer.expire(now)
        pos, frames, size = 0, 0, len(data)
        while pos < size:
            if in_ascii_mode(vm):
                try:
                    text = self.bus.serial_text(vm, data[pos:] if pos else data, channel)
                except Exception:
                    log.exception("module failed on ASCII input %r", data[pos:])
                    return frames
                if text.data:
                    found.append((size - len(text.leftover), index, Output(vm, text.data, ASCII)))
                if in_ascii_mode(vm):
                    return frames
                framer.reset()  # BIN: binary framing starts afresh after the line
                pos = size - len(text.leftover)
                continue
            need = framer.frame_len - framer.pending
            piece = data[pos:pos + need] if pos or need < size else data
            pos += len(piece)
            for frame in framer.feed(piece, now):
                if frames and not self._between_frames(channel):
                    return frames
                frames += 1
                reply = self._frame(vm, frame, channel)
                if reply:
                    found.append((pos, index, Output(vm, reply, BINARY)))
        return frames
