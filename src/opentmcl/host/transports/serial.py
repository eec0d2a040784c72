"""Serial transport through pyserial: RS-232, RS-485 adapters, USB, a pty (TMCM-6212 manual 3.1, 3.2).

    serial:///dev/ttyUSB0?baud=9600        (POSIX path)
    serial://COM3?baud=115200              (Windows port name)
    serial:///dev/pts/5?window=8           (`opentmcl serve --pty`: 8 requests in flight)

`baud` defaults to 9600, the modules' default (global parameter 65). Any other
pyserial port name works too, including pyserial URLs given as
``serial://?port=URL`` (e.g. ``port=opentmcl://TMCM-6212``). Before pyserial opens a port
URL, the hook registered for its scheme (`register_port_handler`) runs, so pyserial knows
handlers that live in other layers: the root package registers ``opentmcl://``.

`window` (default 1) is how many requests `Client.request_many` sends before reading their
replies. A real module's receive buffer is not documented and the manual says "Do not send the
next command before having received the reply!" (TMCM-6212 manual 3.2), so more only on request,
e.g. for our pty server (docs/assumptions.md "Request-many and pipelining").
"""
from __future__ import annotations

import errno
import os
import urllib.parse
from collections.abc import Callable
from typing import Protocol

from ... import registry
from ..errors import TmclConnectionError, TmclTypeError, TmclUrlError
from ..transport import StreamTransport, link_error, log, register_checked, url_query, url_window

DEFAULT_BAUD = 9600


class PyserialPort(Protocol):
    """What the transport uses of a pyserial port (`serial.serial_for_url`)."""

    timeout: float | None

    @property
    def in_waiting(self) -> int: ...

    def read(self, size: int = 1, /) -> bytes: ...

    def write(self, data: bytes, /) -> int | None: ...

    def flush(self) -> None: ...

    def reset_input_buffer(self) -> None: ...

    def close(self) -> None: ...

_PORT_HANDLERS = registry.of(registry.SERIAL_URL_HANDLERS)


def register_port_handler(scheme: str, hook: Callable[[], object] | str) -> None:
    """Run `hook` (or the object a lazy ``"package.module:attribute"`` names) before pyserial opens a
    ``scheme://`` port URL, e.g. to add a package to ``serial.protocol_handler_packages``."""
    register_checked(_PORT_HANDLERS, scheme, hook, "port handler hook")


def prepare_port(port: str) -> None:
    """Run the hook registered for the scheme of a pyserial port URL (none for a device path)."""
    scheme, sep, _ = port.partition("://")
    if not sep or not registry.NAME.fullmatch(scheme.lower()):
        return
    try:
        hook = _PORT_HANDLERS.find(scheme)
    except (ImportError, AttributeError) as exc:
        raise TmclConnectionError(f"the {scheme}:// port handler is not available: {exc}") from None
    if callable(hook):
        hook()


def existing_ports() -> list[str]:
    """The serial ports pyserial finds on this computer (`serial.tools.list_ports`); [] if it cannot tell."""
    try:
        from serial.tools import list_ports

        return sorted(p.device for p in list_ports.comports())
    except Exception:  # listing is a hint only: never let it hide the real error
        return []


def open_error(port: str, exc: BaseException) -> str:
    """One line for a port that cannot be opened: the cause once (pyserial repeats the errno in
    its message) and the likely fix: the ports that exist, or the permission to ask for."""
    code = getattr(exc, "errno", None)
    cause = os.strerror(code) if isinstance(code, int) and code > 0 else str(exc)
    text = f"cannot open serial port {port}: {cause}"
    if code in (errno.EACCES, errno.EPERM):
        return text + " (on Linux: add your user to the 'dialout' group, then log in again)"
    if code == errno.EBUSY:
        return text + " (another program has it open)"
    is_url = "://" in port
    if code in (errno.ENOENT, errno.ENODEV, errno.ENXIO) or (not is_url and code is None and port not in existing_ports()):
        ports = existing_ports()
        found = (f"serial ports here: {', '.join(ports)}" if ports else
                 "no serial port found here: is the adapter plugged in?")
        return f"{text}; {found}"
    return text


class SerialTransport(StreamTransport):
    """A pyserial port; `recv` returns exactly n bytes or raises `TmclTimeout`."""

    def __init__(self, port: str, baud: int = DEFAULT_BAUD, window: int = 1) -> None:
        import serial

        if not isinstance(port, str):
            raise TmclTypeError(f"serial port must be a name or path, got {port!r}")
        prepare_port(port)
        super().__init__()
        self.port = port
        self.window = window
        self.name = f"serial port {port}"
        try:
            self._ser: PyserialPort = serial.serial_for_url(port, baudrate=baud, timeout=0.1, write_timeout=5.0)
        except (serial.SerialException, ValueError, OSError) as exc:
            raise TmclConnectionError(open_error(port, exc)) from None
        log.info("opened %s at %d baud", self.name, baud)

    @property
    def baud(self) -> int:
        """The port's baud rate; settable (the dashboard's module scan tries several)."""
        return int(getattr(self._ser, "baudrate", 0))

    @baud.setter
    def baud(self, value: int) -> None:
        self._ser.baudrate = int(value)  # type: ignore[attr-defined]

    def _write(self, data: bytes) -> None:
        import serial

        try:
            self._ser.write(data)
            self._ser.flush()
        except (serial.SerialException, OSError) as exc:
            raise TmclConnectionError(link_error(self.name, "writing", exc)) from None

    def _read_some(self, timeout: float) -> bytes:
        import serial

        try:
            self._ser.timeout = timeout
            return self._ser.read(max(1, self._ser.in_waiting))
        except (serial.SerialException, OSError) as exc:
            raise TmclConnectionError(f"{self.name}: read failed: {exc}") from None

    def reset_input(self) -> None:
        self._rx.clear()
        if not self._closed:
            try:
                self._ser.reset_input_buffer()
            except Exception:  # pyserial raises various types on a vanished port
                pass

    def _release(self) -> None:
        self._ser.close()


def open_serial(url: urllib.parse.SplitResult) -> SerialTransport:
    """Factory for ``serial:///dev/ttyX?baud=N``, ``serial://COM3?baud=N`` or ``serial://?port=URL``."""
    query = url_query(url, ("port", "baud", "window"))
    window = url_window(query, 1, url.geturl())
    port = query.get("port") or (url.netloc + url.path if url.netloc else url.path)
    if not port:
        raise TmclUrlError(f"serial URL names no port, e.g. serial:///dev/ttyUSB0, got {url.geturl()!r}")
    try:
        baud = int(query.get("baud", DEFAULT_BAUD))
    except ValueError:
        raise TmclUrlError(f"bad baud rate in {url.geturl()!r}") from None
    if baud <= 0:
        raise TmclUrlError(f"bad baud rate {baud}")
    return SerialTransport(port, baud, window)
