"""One serial-framed link to the bus: a pty, a TCP client (TMCM-6212 manual 3.1, 3.2).

A `SerialSession` turns received bytes into 9-byte frames and, for modules in
ASCII mode, text lines (`SerialStream`), hands them to the modules of the bus
and writes the replies back, as a module on an RS-485 line does:

- it waits the telegram pause time (global parameter 75) before a reply
  ("Pause time before the reply via RS485 is sent", manual 5.1; not on a link
  that stands for USB); the manual gives no unit, we use milliseconds
  (docs/assumptions.md);
- with `pace_bytes`, received bytes reach the modules only once they have crossed
  the line at the RS485 baud rate (global parameter 65, ten bit times per byte,
  8N1; the slowest module's rate on a bus), binary frames and ASCII text alike,
  and the reply is sent one byte at a time at the module's rate: a paced
  round trip takes at least the wire time of request and reply, plus GP75;
- unsolicited replies (command 138) arrive through `deliver` and are written
  the same way;
- link faults (`opentmcl serve --faults`, docs/faults.md) act between the received bytes and the
  stream, and on the replies (server/linkfaults.py);
- ASCII echo and reply text (PD28-1021 manual 3.4) is written at once, with
  pacing but without the telegram pause: a terminal user expects the echo of
  a key at once, and the manual ties GP75 to replies "via RS485" only
  (docs/assumptions.md).

The session owns no thread; the endpoint that reads the link calls `receive`.
The inter-byte gap is measured on a "line clock" that stands still while the
session itself is busy (handling frames, writing replies, waiting for the bus
lock): bytes that queued up in the kernel meanwhile were not silence, so a
loaded machine never splits a host's frames (docs/assumptions.md).
"""
from __future__ import annotations

import threading
import time
from collections.abc import Callable

from . import vmapi
from .bus import USB
from .framer import DEFAULT_GAP
from .linkfaults import FaultyLine, link_faults
from .stream import BINARY, SerialStream

BITS_PER_BYTE = 10
"""Start bit, eight data bits, stop bit (8N1)."""


def byte_time(baud: int) -> float:
    """Seconds one byte occupies on the line at `baud`."""
    return BITS_PER_BYTE / baud


def line_byte_time(modules) -> float:
    """Seconds one received byte occupies on a line shared by `modules`: at the slowest of their
    RS485 baud rates (GP65); the caller holds the bus lock."""
    return max(byte_time(vmapi.baud_rate(vm)) for vm in modules)


class SerialSession:
    """Frames a byte stream, talks to the bus, writes replies with pause and pacing."""

    def __init__(self, bus, write: Callable[[bytes], None], *, gap: float = DEFAULT_GAP,
                 pace_bytes: bool = False, clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] = time.sleep, interface: str = "serial") -> None:
        self.bus = bus
        self.interface = interface
        """The link this session stands for (bus.Channel.interface): "usb" ignores the address byte."""
        self._write = write
        self.stream = SerialStream(bus, gap)
        self.pace_bytes = pace_bytes
        self._clock = clock
        self._sleep = sleep
        self._closing = threading.Event()
        self._write_lock = threading.Lock()
        self._readers: dict[int, Callable[[int], int] | None] = {}  # id(vm) -> vmapi.raw_reader(vm)
        self.bytes_received = 0
        """Bytes handled so far (replies written): for diagnostics and tests."""
        self._busy = 0.0  # seconds spent inside `receive`, left out of the line clock
        self._rx_free = float("-inf")  # with pacing: when the last received byte is off the line
        faults = link_faults(bus, interface)
        self.line = None if faults is None else FaultyLine(faults, bus, self._feed, self.send_reply, self._wait, gap)
        """The link's faults (`opentmcl serve --faults`), or None."""

    @property
    def closed(self) -> bool:
        """The link is closing or closed (`close()`, or an endpoint that stops): what the session
        is waiting for (pacing, a telegram pause) ends at once and nothing more is handled."""
        return self._closing.is_set()

    @closed.setter
    def closed(self, value: bool) -> None:
        if value:
            self._closing.set()
        else:
            self._closing.clear()

    def _wait(self, seconds: float) -> None:
        """Sleep `seconds`, or less when the link closes meanwhile (`serve` ends within 2 s of
        SIGTERM even while 4 kB cross a paced 9600-baud line, 4.3 s)."""
        if self._sleep is time.sleep:
            self._closing.wait(seconds)
        else:  # a test's clock
            self._sleep(seconds)

    @property
    def framer(self):
        """The (first module's) framer, for diagnostics."""
        return self.stream.framer

    def receive(self, data: bytes, now: float | None = None) -> int:
        """Handle bytes read from the link; return the number of binary frames completed.

        A module that raises on a frame (a bug: modules answer bad input with a
        status code) is logged and the frame gets no reply; the link lives on.
        """
        before = self.stream.frames
        start = self._clock()
        if self.pace_bytes and data:
            self._wait_on_the_line(len(data), start)
            if self.closed:
                return 0
        line_now = self._clock() - self._busy if now is None else now
        waited = 0.0
        if self.line is not None:  # link faults (server/linkfaults.py)
            waited = self.line.receive(data, line_now)
        else:
            outputs = self.stream.feed(data, line_now, self)
            if len(outputs) == 1:
                vm, out, kind = outputs[0]
                self.send_reply(vm, out, pause=kind == BINARY)
            elif outputs:
                self._send_together(outputs)
        self.bytes_received += len(data)
        if now is None:
            self._busy += self._clock() - start - waited
        return self.stream.frames - before

    def _feed(self, data: bytes, now: float) -> list:
        return self.stream.feed(data, now, self)

    def _wait_on_the_line(self, count: int, now: float) -> None:
        """Pacing: sleep until `count` bytes read at `now` have crossed the line (they follow
        the bytes received before, at the slowest baud rate of the modules on the bus)."""
        with self.bus.lock:
            per_byte = line_byte_time(self.bus.modules)
        self._rx_free = max(self._rx_free, now) + count * per_byte
        wait = self._rx_free - self._clock()
        if wait > 0:
            self._wait(wait)

    def _send_together(self, outputs: list) -> None:
        """Several replies from one read (a pipelining host): those with no telegram pause and no
        pacing due go out in one write, in order; a reply with a pause is written on its own."""
        pending = bytearray()
        for vm, out, kind in outputs:
            if not self.pace_bytes and not self._pause(vm, kind == BINARY):
                pending += out
                continue
            if pending:
                with self._write_lock:
                    self._write(bytes(pending))
                pending.clear()
            self.send_reply(vm, out, pause=kind == BINARY)
        if pending:
            with self._write_lock:
                self._write(bytes(pending))

    def _reader(self, vm) -> Callable[[int], int] | None:
        if id(vm) not in self._readers:
            self._readers[id(vm)] = vmapi.raw_reader(vm)
        return self._readers[id(vm)]

    def _pause(self, vm, pause: bool) -> float:
        """Seconds of telegram pause (GP75, ms) before a reply of `vm`; 0 on USB or if not `pause`."""
        if not pause or self.interface == USB:
            return 0.0
        reader = self._reader(vm)
        if reader is not None:
            return reader(vmapi.GP_TELEGRAM_PAUSE) / 1000.0
        with self.bus.lock:
            return vmapi.global_param(vm, vmapi.GP_TELEGRAM_PAUSE) / 1000.0

    def deliver(self, vm, reply: bytes) -> None:
        """An unsolicited reply (command 138 event) for the host on this link (lost while the link
        is down)."""
        if not self.closed and (self.line is None or not self.line.down()):
            self.send_reply(vm, reply)

    def send_reply(self, vm, reply: bytes, *, pause: bool = True) -> None:
        """Write `reply` after the telegram pause (if `pause`; never on USB: GP75 is the pause "before
        the reply via RS485 is sent"), paced at GP65 if asked."""
        pause = pause and self.interface != USB
        if id(vm) not in self._readers:
            self._readers[id(vm)] = vmapi.raw_reader(vm)
        reader = self._readers[id(vm)]
        if reader is not None:  # a RAM read: no bus lock needed
            wait = reader(vmapi.GP_TELEGRAM_PAUSE) / 1000.0 if pause else 0.0
            per_byte = byte_time(vmapi.baud_rate(vm)) if self.pace_bytes else 0.0
        else:
            with self.bus.lock:
                wait = vmapi.global_param(vm, vmapi.GP_TELEGRAM_PAUSE) / 1000.0 if pause else 0.0
                per_byte = byte_time(vmapi.baud_rate(vm)) if self.pace_bytes else 0.0
        if not wait and not per_byte:
            with self._write_lock:
                self._write(reply)
            return
        with self._write_lock:
            if wait > 0:
                self._wait(wait)
            if per_byte <= 0:
                self._write(reply)
                return
            start = self._clock()
            for i in range(len(reply)):  # a byte is there once its stop bit has crossed the line
                wait = start + (i + 1) * per_byte - self._clock()
                if wait > 0:
                    self._wait(wait)
                if self.closed:
                    return
                self._write(reply[i:i + 1])

    def close(self) -> None:
        self.closed = True
        self.bus.forget(self)
