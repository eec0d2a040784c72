"""The byte pipe between the host library and a module (shared transport contract).

A transport moves bytes and nothing else, like python-can's `BusABC`: the
`Client` builds frames, a transport sends them and returns exactly the number
of bytes asked for, or raises `TmclTimeout`. Concrete transports live in
`opentmcl.host.transports.*` and are chosen by URL scheme in `connect.py`.

`frame_format` tells the client how to frame a request:

- ``"serial"``: nine-byte frames with module address and checksum, as on
  RS-232/RS-485/USB and TCP (TMCM-6212 manual 3.1, 3.2);
- ``"can"``: CAN payloads, one frame per `send`/`recv` call. A request is
  eight bytes (command, type, motor, value, checksum; the module address is
  the CAN ID chosen when the transport was opened); a reply is seven bytes
  (module address, status, command, value) because "the first byte (reply
  address) and the last byte (checksum) are left out" (PD86-1180 manual 4.2);
  the string reply of command 136 is eight bytes, the version string (PD86-1180
  manual 4.6.39).

Every transport logs each frame it sends (``->``) and receives (``<-``) at DEBUG on the logger
``opentmcl.host.transport`` as TMCL text plus the bytes (`frame_text`), e.g.
``-> MVP ABS, 0, 51200  [01 04 00 00 00 00 c8 00 cd]``; the text is built only when that level is
enabled (docs/host.md "Logging").
"""
from __future__ import annotations

import logging
import threading
import time
import urllib.parse
from abc import ABC, abstractmethod
from typing import TYPE_CHECKING

from .errors import TmclConnectionError, TmclTimeout, TmclUrlError, TmclValueError

if TYPE_CHECKING:
    from typing import Self  # annotations only

    from ..protocol.frame import Reply
    from ..registry import Registry

log = logging.getLogger("opentmcl.host.transport")
DEBUG = logging.DEBUG
_MAKING_LOCK = threading.Lock()
"""Held while a transport's `lock` is made (not reading the instance's `__dict__`, which would
slow every attribute look-up on the transport)."""


def _request_text(command: int, type_: int, motor: int, value: int) -> str:
    from ..protocol.opcodes import format_instruction

    text = format_instruction(command, type_, motor, value)
    return text if text is not None else f"command {command}, type {type_}, motor/bank {motor}, value {value}"


def _reply_text(host: int, module: int, status: int, command: int, value: int) -> str:
    """``reply 2<-1 status 100 (...) MVP value 0``; `host` -1 on CAN (no reply address byte)."""
    from ..protocol.opcodes import COMMANDS
    from ..protocol.status import message

    cmd = COMMANDS.get(command)
    name = cmd.mnemonic if cmd is not None and cmd.mnemonic else f"command {command}"
    to = "" if host < 0 else f" to {host}"
    return f"{name} reply from {module}{to}: status {status} ({message(status)}), value {value}"


def frame_text(data: bytes, frame_format: str = "serial", *, request: bool = True) -> str:
    """One frame as TMCL text plus its bytes in hex: a request as the manual writes the
    instruction (``MVP ABS, 0, 51200``), a reply as its addresses, status, command and value.
    The 136 version string reply (host address and eight characters, no checksum) is shown as
    ``version "6212V105" to 2``; anything else (part of a frame, a wrong checksum, ASCII text) as
    its bytes only."""
    raw = bytes(data)
    hexed = f"[{raw.hex(' ')}]"
    if _is_version_reply(raw, frame_format, request):
        return f'version "{raw[1:].decode("ascii")}" to {raw[0]}  {hexed}'
    if frame_format == "can":  # no address byte, no checksum on the request's CAN ID side
        fields = raw[:3] if request and len(raw) == 8 else raw[:4] if not request and len(raw) == 7 else None
        if fields is None:
            return hexed
        number = int.from_bytes(raw[3:7], "big", signed=True)
        if request:
            return f"{_request_text(fields[0], fields[1], fields[2], number)}  {hexed}"
        return f"{_reply_text(-1, fields[0], fields[1], fields[2], number)}  {hexed}"  # module, status, command
    from ..protocol.frame import FrameError, decode_frame

    try:
        b1, b2, b3, b4, number = decode_frame(raw)   # the one nine-byte codec (manual 3.1)
    except FrameError:
        return hexed
    if request:   # address, command, type, motor/bank
        return f"{_request_text(b2, b3, b4, number)}  {hexed}"
    return f"{_reply_text(b1, b2, b3, b4, number)}  {hexed}"   # host, module, status, command


def _is_version_reply(raw: bytes, frame_format: str, request: bool) -> bool:
    """A serial reply of the host address and eight printable characters whose last byte is no
    checksum: the answer to 136 type 0 (a checksummed frame stays a reply)."""
    return (not request and frame_format != "can" and len(raw) == 9 and sum(raw[:8]) & 0xFF != raw[8]
            and all(0x20 <= b < 0x7F for b in raw[1:]))


def log_frame(arrow: str, data: bytes, frame_format: str) -> None:
    """Log one frame at DEBUG (callers check ``log.isEnabledFor(DEBUG)`` first: the hot path pays
    one call when logging is off)."""
    log.debug("%s %s", arrow, frame_text(data, frame_format, request=arrow == "->"))


class Transport(ABC):
    """Abstract byte transport. Implementations must be safe to close twice."""

    frame_format: str = "serial"
    window: int = 1
    """Requests `Client.request_many` may have in flight at once (sent before their replies are
    read). 1 unless the link is known to take more: a real module's receive buffer is not
    documented (docs/assumptions.md "Request-many and pipelining")."""

    @abstractmethod
    def send(self, data: bytes) -> None:
        """Send all of `data`; raise `TmclConnectionError` if the link is gone."""

    def send_many(self, frames: list[bytes]) -> None:
        """Send several frames one after the other (a stream link writes them at once)."""
        for frame in frames:
            self.send(frame)

    def exchange(self, frame: bytes) -> Reply | bytes | None:
        """Send one request frame and return its reply if the link has it at hand at once (an
        in-process module answers when called; as bytes, or as the `Reply` value the module handed
        over), else None: the caller then reads the reply with `recv`. The caller holds `lock`.
        This default only sends."""
        self.send(frame)
        return None

    def exchange_many(self, frames: list[bytes]) -> list[bytes] | None:
        """`exchange` of a window of frames (`send_many`): their replies in order if the link has
        them all at hand at once, else None. The caller holds `lock`. This default only sends."""
        self.send_many(frames)
        return None

    @abstractmethod
    def recv(self, n: int, timeout: float) -> bytes:
        """Return exactly `n` bytes, waiting at most `timeout` seconds, else raise `TmclTimeout`.

        Bytes that arrived before a timeout stay buffered for the next call: the client listens
        for event replies in short slices, and a frame may straddle two of them.
        """

    @abstractmethod
    def close(self) -> None:
        """Release the link (idempotent)."""

    # Optional hooks with defaults that suit real (wall-clock) links.

    def reset_input(self) -> None:
        """Discard bytes already received but not read (used after a garbled reply)."""
        return None

    def sleep(self, seconds: float) -> None:
        """Let `seconds` pass on the module's clock (real links: wall clock)."""
        if seconds > 0:
            time.sleep(seconds)

    def monotonic(self) -> float:
        """The clock that `timeout`/`sleep` are measured on (real links: wall clock)."""
        return time.monotonic()

    def local_module(self, address: int) -> object | None:
        """The virtual module in this process that answers `address`, or None (real links).
        Lets the debugger read state the wire does not carry, such as the program flags."""
        return None

    _lock: threading.RLock | None = None   # `lock`, once made

    @property
    def lock(self) -> threading.RLock:
        """The link's one re-entrant lock, made on first use: a `Client` holds it for each request,
        and whoever works on what lies behind the link outside the client holds it too (the
        dashboard reads an in-process module under it)."""
        lock = self._lock
        if lock is None:
            with _MAKING_LOCK:  # two threads at the first use make one lock
                lock = self._lock
                if lock is None:
                    lock = self._lock = threading.RLock()
        return lock

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class StreamTransport(Transport):
    """A byte stream (serial line, TCP socket). Bytes that arrived before a timeout stay in a
    receive buffer for the next `recv`; subclasses supply `_read_some`, `_write` and `_release`."""

    frame_format = "serial"
    name = "link"

    def __init__(self) -> None:
        self._rx = bytearray()
        self._closed = False

    @abstractmethod
    def _read_some(self, timeout: float) -> bytes:
        """Whatever arrives within `timeout` (b"" if nothing); TmclConnectionError if the link broke."""

    @abstractmethod
    def _write(self, data: bytes) -> None: ...

    @abstractmethod
    def _release(self) -> None:
        """Close the underlying link (may raise; close() swallows it)."""

    def _check_open(self) -> None:
        if self._closed:
            raise TmclConnectionError(f"{self.name} is closed")

    def send(self, data: bytes) -> None:
        self._check_open()
        if log.isEnabledFor(DEBUG):
            log_frame("->", data, self.frame_format)
        self._write(data)

    def send_many(self, frames: list[bytes]) -> None:
        """The frames in one write: a window of requests in flight (`window`)."""
        self._check_open()
        if log.isEnabledFor(DEBUG):
            for frame in frames:
                log_frame("->", frame, self.frame_format)
        self._write(b"".join(frames))

    def read_some(self, timeout: float) -> bytes:
        """The bytes the link delivers within `timeout` seconds, unframed and unlogged (b"" if
        none); TmclConnectionError if the link broke or is closed. For a relay that takes the link
        over (the capture proxy): it reads past `recv`'s buffer, so do not mix the two."""
        self._check_open()
        return self._read_some(timeout)

    def recv(self, n: int, timeout: float) -> bytes:
        self._check_open()
        deadline = time.monotonic() + max(0.0, timeout)
        while len(self._rx) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TmclTimeout(f"{self.name}: no reply within {timeout:g} s "
                                  f"({len(self._rx)} of {n} bytes received)")
            self._rx += self._read_some(left)
        out = bytes(self._rx[:n])
        del self._rx[:n]
        if log.isEnabledFor(DEBUG):
            log_frame("<-", out, self.frame_format)
        return out

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        try:
            self._release()
        except Exception:  # closing a vanished port or socket must not raise
            pass


def link_error(name: str, action: str, exc: OSError) -> str:
    """One sentence for a link that broke while `action` ("sending", "receiving"): the cause once
    (no bare errno) and what to check."""
    if isinstance(exc, (BrokenPipeError, ConnectionResetError, ConnectionAbortedError)):
        return (f"{name}: the other end closed the connection while {action}; check that the server "
                "or module is still running, then connect again")
    if isinstance(exc, TimeoutError):
        return f"{name}: {action} timed out; check that the server or module still reads its link"
    cause = exc.strerror or str(exc)
    return f"{name}: {action} failed: {cause}"


def url_window(query: dict[str, str], default: int, url: str) -> int:
    """``?window=N`` of a stream URL: requests in flight in `Client.request_many`, 1..MAX_WINDOW."""
    text = query.get("window")
    if text is None:
        return default
    try:
        window = int(text)
    except ValueError:
        raise TmclUrlError(f"bad window {text!r} in {url!r}; give a whole number 1..{MAX_WINDOW}") from None
    if not 1 <= window <= MAX_WINDOW:
        raise TmclUrlError(f"window must be 1..{MAX_WINDOW}, got {window}")
    return window


MAX_WINDOW = 64
"""The most requests a stream link may have in flight (`?window=`)."""


def url_query(url: urllib.parse.SplitResult, known: tuple[str, ...]) -> dict[str, str]:
    """The query of a transport URL as a dict; a key the transport does not know (a typo such as
    ``?baudrate=``) is a TmclConnectionError instead of being ignored."""
    query = dict(urllib.parse.parse_qsl(url.query, keep_blank_values=True))
    unknown = sorted(set(query) - set(known))
    if unknown:
        raise TmclUrlError(f"unknown {', '.join(repr(k) for k in unknown)} in {url.scheme}:// URL "
                                  f"(it takes {', '.join(known)})")
    return query



def register_checked(registry: Registry, scheme: str, target: object, what: str) -> None:
    """Register `target` (callable or lazy ``"package.module:attribute"``) under `scheme`;
    a bad target or scheme name is a `TmclValueError` naming `what` it should have been."""
    if not (callable(target) or isinstance(target, str)):
        raise TmclValueError(f"a {what} must be callable or 'module:attribute', got {target!r}")
    try:
        registry.register(scheme, target)
    except ValueError as exc:
        raise TmclValueError(str(exc)) from None
