"""pyserial port class for ``opentmcl://`` URLs: virtual modules in this process.

    opentmcl://TMCM-6212                       one module at address 1
    opentmcl://TMCM-6212@1,TMCM-1180@2         two modules on one bus
    opentmcl://TMCM-6212?eeprom=/tmp/ee.json&gap=0.1&pace=1
    opentmcl://TMCM-6212?interface=rs485       filter by address (default: usb for one module)

Bytes written to the port are framed into 9-byte TMCL frames (TMCM-6212
manual 3.1) and offered to every module on the bus (`interface=usb`, the default
for a single module: whatever the address byte; rs485/rs232: by address); the modules' replies
become readable after the telegram pause (global parameter 75, manual 5.1),
and with ``pace=1`` both directions take their wire time at the RS485 baud
rate (parameter 65): written bytes reach the modules only after crossing the
line. The modules run in real time: their virtual time follows the wall clock, advanced whenever the
port is used, so a move started by a write has progressed by the next read.
Unsolicited replies (command 138, manual 3.6.35) are readable like any other.
Modules that have ASCII mode (command 139, PD28-1021 manual 3.4) read the
written bytes as text lines while in it, as on the other serial endpoints.
No thread is started; closing the port flushes the EEPROM files. Replies
nobody reads are kept up to `RX_BUFFER` bytes (a terminal's input buffer) and
then dropped, as on the pty endpoint.

The baud rate, parity etc. set on the port are accepted and ignored.

The class derives from pyserial's platform `serial.Serial` (overriding every
method that would touch a file descriptor), so code that checks
``isinstance(port, serial.Serial)`` - PyTrinamic's `SerialTmclInterface`
does - accepts it.
"""
from __future__ import annotations

import math
import threading
import time
import urllib.parse
from typing import TypedDict

import serial
from serial.serialutil import PortNotOpenError, SerialException, Timeout

from ..modules.addresses import address_error
from ..server import vmapi
from ..server.bus import SERIAL_INTERFACES, USB, ModuleBus, default_interface, interface_error
from ..server.framer import DEFAULT_GAP
from ..server.session import byte_time, line_byte_time
from ..server.stream import BINARY, SerialStream

SCHEME = "opentmcl"
POLL = 0.002
RX_BUFFER = 4096
"""Bytes of unread replies kept; more are dropped (the size of a Linux tty input buffer)."""


class PortOptions(TypedDict):
    """What an ``opentmcl://`` URL asks for (see the module docstring)."""

    modules: list[tuple[str, int]]
    """(profile name, module address) of each module on the bus."""
    eeprom: list[str]
    gap: float
    pace: bool
    interface: str


def parse_url(url: str) -> PortOptions:
    """Split an ``opentmcl://`` URL into module specs and options; ValueError when malformed."""
    parts = urllib.parse.urlsplit(url)
    if parts.scheme.lower() != SCHEME:
        raise ValueError(f"expected an {SCHEME}:// URL, got {url!r}")
    modules = _module_specs(urllib.parse.unquote(parts.netloc + parts.path).strip("/"), url)
    eeprom, gap, pace, interface = _query_options(parts.query, url)
    if interface is None:
        interface = default_interface(modules, pace)
    problem = interface_error(interface, modules, pace)
    if problem:
        raise ValueError(problem)
    if len(eeprom) > len(modules):
        raise ValueError("more eeprom files than modules")
    return PortOptions(modules=modules, eeprom=eeprom, gap=gap, pace=pace, interface=interface)


def _module_specs(spec: str, url: str) -> list[tuple[str, int]]:
    """``NAME[@ADDR][,NAME@ADDR...]`` -> [(name, address), ...]; without ``@`` the n-th module is at n."""
    names = [p.strip() for p in spec.split(",") if p.strip()]
    if not names:
        raise ValueError(f"{SCHEME}:// URL names no module, e.g. {SCHEME}://TMCM-6212")
    modules = []
    for i, item in enumerate(names):
        name, sep, addr = item.partition("@")
        if sep:
            try:
                address = int(addr, 0)
            except ValueError:
                raise ValueError(f"bad module address {addr!r} in {url!r}") from None
        else:
            address = 1 + i
        modules.append((name.strip(), address))
    problem = address_error([a for _, a in modules])
    if problem:
        raise ValueError(problem)
    return modules


def _query_options(query: str, url: str) -> tuple[list[str], float, bool, str | None]:
    """(eeprom files, gap, pace, interface or None for the default) of the URL's query."""
    eeprom: list[str] = []
    gap, pace, interface = DEFAULT_GAP, False, None
    for key, value in urllib.parse.parse_qsl(query, keep_blank_values=True):
        if key == "eeprom":
            eeprom = value.split(",")
        elif key == "gap":
            gap = _gap(value)
        elif key == "pace":
            pace = value.lower() in ("1", "true", "yes", "on")
        elif key == "interface":
            if value not in SERIAL_INTERFACES:
                raise ValueError(f"bad interface {value!r}; use one of {', '.join(SERIAL_INTERFACES)}")
            interface = value
        else:
            raise ValueError(f"unknown option {key!r} in {url!r} (known: eeprom, gap, pace, interface)")
    return eeprom, gap, pace, interface


def _gap(value: str) -> float:
    """The telegram gap in seconds: a positive, finite number."""
    try:
        gap = float(value)
    except ValueError:
        raise ValueError(f"bad gap {value!r}") from None
    if not 0 < gap < float("inf"):
        raise ValueError(f"gap must be a positive number of seconds, got {value!r}")
    return gap


class Serial(serial.Serial):
    """A pyserial port whose other end is a bus of virtual modules."""

    interface = "serial"
    """Replaced at open by the URL's `interface` (bus.Channel.interface)."""
    is_open: bool

    def open(self) -> None:
        if self._port is None:
            raise SerialException("port must be configured before it can be used")
        if self.is_open:
            raise SerialException("port is already open")
        try:
            options = parse_url(self._port)
        except ValueError as exc:
            raise SerialException(str(exc)) from None
        from ..firmware.vm import VirtualModule

        modules = []
        for i, (name, address) in enumerate(options["modules"]):
            eeprom = options["eeprom"][i] if i < len(options["eeprom"]) else None
            try:
                modules.append(VirtualModule(name, address=address, eeprom=eeprom or None))
            except KeyError as exc:
                raise SerialException(f"unknown module {name!r}: {exc}") from None
            except Exception as exc:  # e.g. an EEPROM file that is not ours
                raise SerialException(f"cannot create {name}: {exc}") from None
        self._lock = threading.RLock()
        self._bus = ModuleBus(modules)
        self._stream = SerialStream(self._bus, options["gap"])
        self._pace = options["pace"]
        self.interface = options["interface"]
        self._rx: list[tuple[float, int]] = []  # (time the byte becomes readable, byte)
        self._tx: list[tuple[float, bytes]] = []  # pace=1: (time the bytes reach the modules, bytes)
        self._tx_free = float("-inf")
        self.dropped = 0
        """Reply bytes dropped because `RX_BUFFER` unread bytes were waiting."""
        self.is_open = True

    def close(self) -> None:
        if not self.is_open:
            return
        self.is_open = False
        with self._lock:
            for vm in self._bus.modules:
                close = getattr(vm, "close", None)
                if callable(close):
                    close()

    def from_url(self, url: str) -> str:
        parse_url(url)
        return url

    def _reconfigure_port(self, force_update: bool = False) -> None:
        """Baud rate and framing settings are accepted and ignored."""

    # -- data --------------------------------------------------------------
    def _queue(self, vm, reply: bytes, pause: bool = True, at: float | None = None) -> None:
        """Make `reply` readable after the telegram pause (binary replies only), paced at GP65 if asked;
        `at` is when the request reached the module (default: now)."""
        now = time.monotonic() if at is None else at
        pause = pause and self.interface != USB   # GP75: "before the reply via RS485 is sent"
        start = now + (vmapi.global_param(vm, vmapi.GP_TELEGRAM_PAUSE) / 1000.0 if pause else 0.0)
        if self._rx:
            start = max(start, self._rx[-1][0])
        per_byte = byte_time(vmapi.baud_rate(vm)) if self._pace else 0.0
        room = RX_BUFFER - len(self._rx)
        if room < len(reply):
            self.dropped += len(reply) - max(room, 0)
            reply = reply[:max(room, 0)]
        for i, b in enumerate(reply):
            self._rx.append((start + (i + 1) * per_byte, b))

    def deliver(self, vm, reply: bytes) -> None:
        """Unsolicited reply from the bus (command 138 event)."""
        self._queue(vm, reply)

    def _update(self) -> int:
        """Advance the modules to now, hand them the written bytes that have crossed the line,
        collect events; return readable byte count."""
        self._feed_arrived()
        for channel, vm, event in self._bus.poll():
            channel.deliver(vm, event)
        now = time.monotonic()
        n = 0
        for ready, _ in self._rx:
            if ready > now:
                break
            n += 1
        return n

    @property
    def in_waiting(self) -> int:
        if not self.is_open:
            raise PortNotOpenError()
        with self._lock:
            return self._update()

    def read(self, size: int = 1) -> bytes:
        if not self.is_open:
            raise PortNotOpenError()
        timeout = Timeout(self._timeout)
        out = bytearray()
        while len(out) < size:
            with self._lock:
                n = min(self._update(), size - len(out))
                if n:
                    out += bytes(b for _, b in self._rx[:n])
                    del self._rx[:n]
                    continue
            if timeout.expired():
                break
            left = timeout.time_left()
            time.sleep(POLL if left is None else max(0.0, min(POLL, left)))
        return bytes(out)

    def write(self, data) -> int:
        if not self.is_open:
            raise PortNotOpenError()
        data = bytes(data)
        with self._lock:
            now = time.monotonic()
            if self._pace and data:  # the bytes reach the modules once they crossed the line
                per_byte = line_byte_time(self._bus.modules)
                self._tx_free = max(self._tx_free, now) + len(data) * per_byte
                self._tx.append((self._tx_free, data))
                self._feed_arrived()
            else:
                self._feed(data, now)
        return len(data)

    def _feed(self, data: bytes, at: float) -> None:
        for vm, out, kind in self._stream.feed(data, at, self):
            self._queue(vm, out, pause=kind == BINARY, at=at)

    def _feed_arrived(self) -> None:
        now = time.monotonic()
        while self._tx and self._tx[0][0] <= now:
            at, data = self._tx.pop(0)
            self._feed(data, at)

    def reset_input_buffer(self) -> None:
        if not self.is_open:
            raise PortNotOpenError()
        with self._lock:
            self._update()
            self._rx.clear()

    def reset_output_buffer(self) -> None:
        """Written bytes still on the (paced) line are discarded."""
        if not self.is_open:
            raise PortNotOpenError()
        with self._lock:
            self._feed_arrived()
            self._tx.clear()

    @property
    def out_waiting(self) -> int:
        """Written bytes still on the (paced) line."""
        with self._lock:
            self._feed_arrived()
            if not self._tx:
                return 0
            per_byte = line_byte_time(self._bus.modules)
            # bytes whose stop bit has not crossed the line yet (the line is busy until the last end)
            return min(sum(len(data) for _, data in self._tx),
                       math.ceil((self._tx[-1][0] - time.monotonic()) / per_byte - 1e-9))

    def flush(self) -> None:
        """Wait until the written bytes have reached the modules (at once without pacing)."""
        if not self.is_open:
            raise PortNotOpenError()
        with self._lock:
            last = self._tx[-1][0] if self._tx else None
        if last is not None:
            time.sleep(max(0.0, last - time.monotonic()))
        with self._lock:
            self._feed_arrived()

    def fileno(self) -> int:
        raise SerialException("an opentmcl:// port has no file descriptor")

    def nonblocking(self) -> None:
        pass

    def cancel_read(self) -> None:
        pass

    def cancel_write(self) -> None:
        pass

    def send_break(self, duration: float = 0.25) -> None:
        if not self.is_open:
            raise PortNotOpenError()

    def set_input_flow_control(self, enable: bool = True) -> None:
        pass

    def set_output_flow_control(self, enable: bool = True) -> None:
        pass

    # -- modem lines: a virtual port has none worth simulating --------------
    def _update_break_state(self) -> None:
        pass

    def _update_rts_state(self) -> None:
        pass

    def _update_dtr_state(self) -> None:
        pass

    @property
    def cts(self) -> bool:
        return True

    @property
    def dsr(self) -> bool:
        return True

    @property
    def ri(self) -> bool:
        return False

    @property
    def cd(self) -> bool:
        return True

    @property
    def modules(self) -> list:
        """The virtual modules on this port's bus (for tests and tools)."""
        return self._bus.modules
