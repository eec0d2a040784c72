"""Request/reply client over any `Transport` (TMCM-6212 manual 3.1, 3.2, 3.6.35, 3.6.36).

One request is in flight at a time ("Do not send the next command before
having received the reply!", manual 3.2) unless `request_many` is asked to send
a window of them (`Transport.window`); the link's lock (`Transport.lock`) lets
threads share a client. Replies are matched to the request by module address and
command number; unsolicited "target position reached" replies (status 128,
command 138) that arrive in between are kept and handed to `wait_position_reached`.

One path for every link: a request checked once is kept ready to send; the transport
sends it (`Transport.exchange`, which in process may hand the reply over at once);
the first frame, when it is the plain reply asked for, is decoded at once, and
anything else is read by the general rule (`_read_plain`, `_read_reply`).

Replies carry no sequence number, so after a reply was lost, late or garbled the client brings
the link back in step before its next request to that module: it sends a read whose reply no
late reply can be mistaken for (`FENCES`) and discards everything before that reply. While the
module suppresses replies (GP255 = 1, "the reply will not be suppressed for GAP, GGP and GIO",
TMCM-6212 manual 5.1) a request whose reply may be suppressed is followed by GGP 255, which is
always answered: a reply before it belongs to the request (docs/host.md "Lost, late and garbled
replies").
"""
from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

from ..protocol.frame import FRAME_LEN, FrameError, Reply, Request, checksum_ok, to_int32
from ..protocol.opcodes import (
    ALWAYS_ANSWERED,
    GET_APPLICATION_STATUS,
    GET_FIRMWARE_VERSION,
    READ_PROGRAM_MEMORY,
    REQUEST_TARGET_REACHED_EVENT,
    UNANSWERED,
    Op,
)
from ..protocol.replies import MemoryReply, is_version_request
from ..protocol.status import Status, is_success
from .errors import (
    TmclAddressError,
    TmclBatchError,
    TmclChecksumError,
    TmclProtocolError,
    TmclStatusError,
    TmclTimeout,
    TmclTypeError,
    TmclValueError,
    check_int,
    check_seconds,
    check_timeout,
    describe_request,
)
from .transport import Transport

if TYPE_CHECKING:
    from ..modules.profile import ModuleProfile
    from .module import Module

_GAP, _SGP, _GGP, _GIO = int(Op.GAP), int(Op.SGP), int(Op.GGP), int(Op.GIO)  # plain ints: the request path
SUPPRESS_REPLY = 255  # GP255 "Suppress reply" (TMCM-6212 manual 5.1)
FENCES = ((_GGP, 66, 0), (_GAP, 1, 0), (GET_FIRMWARE_VERSION, 1, 0), (_GIO, 0, 0), (GET_APPLICATION_STATUS, 0, 0))
"""Reads every module answers (serial address GP66, actual position AP1, binary version, input 0,
program status): the first whose command no lost request to that module had brings the link back
in step."""
CAN_REPLY_LEN = 7  # module address, status, command, value (PD86-1180 manual 4.2)
CAN_VERSION_LEN = 8  # the eight characters of the version string (PD86-1180 manual 4.6.39)
_WAIT_SLICE = 0.05  # seconds the lock is held at a time while waiting for an event
MAX_BATCH = 256
"""The most requests one `Client.request_many` call takes (a longer batch: `TmclBatchError`)."""
_BODY = struct.Struct(">BBBBi")  # the first eight bytes of a frame (manual 3.1)
_VALUE = struct.Struct(">i")  # the value of a CAN reply, after module address, status and command
MAX_PLAIN = 1024
"""The most checked requests a `Client` keeps ready to send (then it starts afresh)."""


_new_tuple = tuple.__new__  # `_new_tuple(Reply, fields)`: a Reply from the unpacked fields at C speed
_NO_REPLY = Reply(0, 0, 0, 0, 0)


@dataclass(frozen=True, slots=True)
class VersionReply:
    """The special reply of command 136 type 0: host address and an 8-character string, no checksum
    (PD86-1180 manual 4.6.39 "Special reply format of command 136")."""

    reply_address: int
    module_address: int  # the address the request went to (the frame does not carry it)
    text: str

    status: ClassVar[int] = Status.OK
    command: ClassVar[int] = GET_FIRMWARE_VERSION

    @property
    def value(self) -> str:
        return self.text


Answer = Reply | VersionReply | MemoryReply | None
"""What `Client.request` returns: a `Reply`, or the special replies of command 136 type 0
(`VersionReply`) and 134 (`MemoryReply`), or None for command 137, which has no reply."""


def _check_byte(name: str, value: int) -> int:
    check_int(value, name)
    if not 0 <= value <= 255:
        raise TmclValueError(f"{name} must be 0..255, got {value}")
    return value


def _check_value(value: int) -> int:
    check_int(value, "value")
    if not -(2**31) <= value <= 2**32 - 1:
        raise TmclValueError(f"value {value} does not fit in 32 bits")
    return to_int32(value)


def has_special_reply(command: int, type: int) -> bool:
    """True for the requests not answered in the 9-byte reply format of manual 3.2: 134 (read
    program memory), 136 type 0 (version string) and 137 (no reply)."""
    return command in UNANSWERED or command == READ_PROGRAM_MEMORY or is_version_request(command, type)


def check_address(value: int) -> int:
    """A module address: an int 0..255 (the address byte of the frame, manual 3.1)."""
    return _check_byte("address", value)


class _Plain:
    """A checked request answered in the reply format of manual 3.2, ready to send."""

    __slots__ = ("frame", "head", "fields", "request", "last", "seen", "silent", "quiets")

    def __init__(self, frame: bytes, head: bytes, request: Request) -> None:
        self.frame = frame
        """The request on the wire: nine bytes (eight on CAN, where the CAN ID carries the address)."""
        self.head = head
        """Module address, status 100 and command: the bytes after the reply address of its plain
        reply (the first three bytes of a CAN reply)."""
        self.fields = tuple(head)
        """The same as the fields of a `Reply` (`reply[1:4]`)."""
        self.request = request
        self.last: tuple[bytes, Reply] = (b"", _NO_REPLY)
        """The last plain reply read, as received and decoded: the same bytes again decode alike."""
        self.seen: Reply = _NO_REPLY
        """The last plain reply handed over as a `Reply` value (`Transport.exchange`): the same
        object again needs no look."""
        self.silent = request.command not in ALWAYS_ANSWERED
        """GP255 = 1 suppresses its reply when it succeeds."""
        self.quiets = request.command == _SGP and request.type == SUPPRESS_REPLY and request.motor == 0 \
            and request.value == 1
        """SGP 255, 0, 1: its own reply is suppressed already."""


_Key = tuple[int, int, int, int, int]
"""Module address, command, type, motor/bank and value of a request, as the caller gave them."""


class Client:
    """Sends TMCL requests through a transport and returns the matching replies.

    `address` is the default module address (1 by default, as shipped), `host_address`
    the reply address the module uses (global parameter 76, default 2).
    """

    def __init__(self, transport: Transport, *, address: int = 1, host_address: int = 2,
                 timeout: float = 5.0):
        if not isinstance(transport, Transport):
            raise TmclTypeError(f"transport must be a Transport, got {type(transport).__name__}")
        self.transport = transport
        self.address = _check_byte("address", address)
        self.host_address = _check_byte("host_address", host_address)
        self.timeout = check_timeout(timeout)
        self.stray_replies = 0  # replies received that matched no request (counted, then dropped)
        self._events: dict[int, int] = {}  # module address -> OR of motor masks not yet consumed
        self._lock = transport.lock  # one lock per link: the client's requests and work behind it
        self._dirty = False  # a reply was lost or garbled: discard pending input before the next request
        self._held = bytearray()  # reply bytes taken from the transport, not read yet (empty between requests)
        self._plain: dict[_Key, _Plain] = {}  # checked requests, ready to send (`_check`)
        self._lost: dict[int, set[int]] = {}  # module address -> commands whose reply may still come
        self._quiet: set[int] = set()  # module addresses that suppress replies (GP255 = 1, as last seen)
        self._can = transport.frame_format == "can"
        self._exchange = transport.exchange

    # ------------------------------------------------------------------ requests

    def request(self, command: int, type: int = 0, motor: int = 0, value: int = 0, *,
                address: int | None = None, timeout: float | None = None) -> Answer:
        """Send one request and return its reply; raise `TmclStatusError` unless the status is 100/101.

        Command 136 type 0 returns a `VersionReply`, command 134 a `MemoryReply` (the stored
        instruction); command 137 sends no reply and returns None.
        """
        target = self.address if address is None else address
        if target.__class__ is command.__class__ is type.__class__ is motor.__class__ is value.__class__ is int:
            plain = self._plain.get((target, command, type, motor, value))
            if plain is not None:  # the same plain ints were checked before
                return self._ask(plain, timeout)
        checked, wait = self._check(command, type, motor, value, address, timeout)
        if isinstance(checked, _Plain):
            return self._ask(checked, wait)
        with self._lock:
            self._send(checked, wait)
            return self._read_answer(checked, wait)

    def reply(self, command: int, type: int = 0, motor: int = 0, value: int = 0, *,
              address: int | None = None, timeout: float | None = None) -> Reply:
        """`request` for a command answered in the reply format of manual 3.2. Commands 134,
        136 type 0 and 137 answer otherwise (or not at all): TmclValueError, nothing is sent."""
        target = self.address if address is None else address
        if target.__class__ is command.__class__ is type.__class__ is motor.__class__ is value.__class__ is int:
            plain = self._plain.get((target, command, type, motor, value))
            if plain is not None:
                return self._ask(plain, timeout)
        checked, wait = self._check(command, type, motor, value, address, timeout)
        if not isinstance(checked, _Plain):
            raise TmclValueError(f"command {command} type {type} has no reply in the normal format "
                                 "(manual 3.2); use Client.request")
        return self._ask(checked, wait)

    def _check(self, command: int, type: int, motor: int, value: int, address: int | None,
               timeout: float | None) -> tuple[_Plain | Request, float]:
        """The checked request (TmclValueError/TmclTypeError if it is not one) and the time-out
        for its reply. A request answered in the format of manual 3.2 comes back as a `_Plain`,
        kept for the next request with the same arguments (up to `MAX_PLAIN` of them); the
        others (134, 136 type 0, 137) as their `Request`."""
        req, wait = self._prepare(command, type, motor, value, address, timeout)
        if has_special_reply(req.command, req.type):
            return req, wait
        plain = _Plain(self._wire(req), bytes((req.address, Status.OK, req.command)), req)
        kept = self._plain
        if len(kept) >= MAX_PLAIN:
            kept.clear()
        kept[(req.address, command, type, motor, value)] = plain
        return plain, wait

    def _ask(self, plain: _Plain, timeout: float | None) -> Reply:
        """Send a plain request and return its reply."""
        wait = self.timeout if timeout is None else check_timeout(timeout)
        lock = self._lock
        lock.acquire()
        try:
            if self._dirty or self._lost:
                self._in_step(plain.request, wait)
            if plain.silent and (self._quiet or plain.quiets):
                return self._ask_quiet(plain, wait)
            raw = self._exchange(plain.frame)
            if raw.__class__ is Reply:  # handed over by an in-process module: nothing to decode
                if raw is plain.seen:  # the same reply object as last time, checked then
                    return raw
                if raw[1:4] == plain.fields:  # the plain reply asked for
                    plain.seen = raw
                    return raw
                raw = raw.encode()  # anything else: read as bytes, by the general rule
            return self._read_plain(plain, wait, raw)  # type: ignore[arg-type]
        finally:
            lock.release()

    # ------------------------------------------------------------------ keeping in step

    def _in_step(self, req: Request, timeout: float) -> None:
        """Before `req`: discard what is left of a lost or garbled reply; after a reply of its
        module was lost, late or garbled, send a fence and read up to its reply (`FENCES`)."""
        self._reset_input()
        late = self._lost.get(req.address)
        if not late:
            return
        free = [f for f in FENCES if f[0] not in late]
        if not free:  # every read a fence could be was lost too: the link is beyond telling
            del self._lost[req.address]
            return
        command, type_, motor = free[0]
        fence = Request(req.address, command, type_, motor, 0)
        self.transport.send(self._wire(fence))
        deadline = self.transport.monotonic() + timeout
        try:
            while True:
                reply = self._next_frame(fence, deadline, timeout)
                if self._same_module(reply, fence) and reply.command == command:
                    break
                self.stray_replies += 1
        except TmclTimeout as exc:
            raise TmclTimeout(f"{exc}; it was sent to bring the link back in step after a lost reply, "
                              f"and {describe_request(req)} was not sent") from None
        self._lost.pop(req.address, None)

    def _mark_lost(self, req: Request) -> None:
        """The reply to `req` may still come (it timed out or came garbled)."""
        self._lost.setdefault(req.address, set()).add(req.command)
        self._dirty = True

    def _ask_quiet(self, plain: _Plain, timeout: float) -> Reply:
        """A request whose reply GP255 may suppress, followed by GGP 255 (always answered): a reply
        of the request before the fence's is its reply, none means it succeeded silently (a
        `Reply` with status 100 and value 0 is returned). The fence's value is the module's GP255."""
        req = plain.request
        fence = Request(req.address, _GGP, SUPPRESS_REPLY, 0, 0)
        self.transport.send_many([plain.frame, self._wire(fence)])
        deadline = self.transport.monotonic() + timeout
        answer: Reply | None = None
        while True:
            try:
                reply = self._next_frame(req, deadline, timeout)
            except (TmclTimeout, TmclProtocolError):
                self._mark_lost(fence)
                raise
            if not self._same_module(reply, req):
                self.stray_replies += 1
            elif reply.command == req.command and answer is None:
                answer = reply
            elif reply.command == _GGP:
                break
            else:
                self.stray_replies += 1
        if is_success(reply.status) and reply.value == 1:
            self._quiet.add(req.address)
        else:
            self._quiet.discard(req.address)
        if answer is None:
            return Reply(self.host_address, req.address, Status.OK, req.command, 0)
        if not is_success(answer.status):
            raise TmclStatusError(answer.status, req, answer)
        return answer

    def _read_plain(self, plain: _Plain, timeout: float, raw: bytes | None) -> Reply:
        """The reply to `plain`, sent; the caller holds the lock.

        `raw` is the reply when the transport had it at hand (`Transport.exchange`), else the first
        reply frame is read here. The common case, that frame is the plain reply of this module
        and command (status 100, a good checksum), is decoded at once (the bytes of the last one
        are not even decoded again). Anything else goes back in front of the bytes to read, and
        the general rule (`_read_reply`) reads from there: events kept, strays counted, errors
        raised."""
        deadline = None
        if raw is None:
            size = CAN_REPLY_LEN if self._can else FRAME_LEN
            held = self._held
            if len(held) >= size:  # a window's replies that were at hand (`request_many`)
                raw = bytes(held[:size])
                del held[:size]
            else:
                deadline = self.transport.monotonic() + timeout
                try:
                    raw = self._recv(size, deadline)
                except TmclTimeout:
                    raise self._no_reply(plain.request, timeout) from None
        last = plain.last
        if raw == last[0]:
            return last[1]
        if self._can:  # the reply address is the client's `host_address`, not on the wire: decoded each time
            if raw[:3] == plain.head:
                return Reply(self.host_address, raw[0], raw[1], raw[2], _VALUE.unpack_from(raw, 3)[0])
        elif raw[1:4] == plain.head and sum(raw[:8]) & 0xFF == raw[8]:
            reply = _new_tuple(Reply, _BODY.unpack_from(raw))
            plain.last = (raw, reply)
            return reply
        self._held[:0] = raw
        return self._read_reply(plain.request, timeout, deadline)

    def read_memory(self, index: int, *, address: int | None = None,
                    timeout: float | None = None) -> MemoryReply:
        """Command 134: the instruction stored at program memory `index` (manual 3.6.36)."""
        req, timeout = self._prepare(READ_PROGRAM_MEMORY, 0, 0, index, address, timeout)
        with self._lock:
            self._send(req, timeout)
            return self._read_memory(req, timeout)

    def request_many(self, requests: Sequence[tuple[int, int, int, int]], *, address: int | None = None,
                     timeout: float | None = None) -> list[Answer]:
        """Send several requests (``(command, type, motor, value)`` tuples) to `address` and return
        their answers in order, each as `request` returns it.

        Every request is checked before anything is sent (a bad one: TmclValueError/TmclTypeError
        naming its index; more than `MAX_BATCH`: TmclBatchError). Up to `Transport.window` requests
        are in flight at once (in-process: all of them, after one time sync). Every request is sent
        and every reply read, also after one answered with an error status; then the first
        `TmclStatusError` is raised, with its `index` in the batch and the `answers` of all (None
        at a failed one), so the link stays in step. A timeout stops the batch at once
        (`TmclTimeout`, requests after the window not sent); replies still on the way are
        discarded before the next request, as after a timeout of `request`. `timeout` is per reply.
        """
        batch, timeout = self._prepare_many(requests, address, timeout)
        answers: list[Answer] = []
        first: TmclStatusError | None = None
        with self._lock:
            quiet = any(isinstance(i, _Plain) and i.silent and (i.quiets or i.request.address in self._quiet)
                        for i in batch)
            window = 1 if quiet else max(1, self.transport.window)  # suppressed replies: one at a time
            for start in range(0, len(batch), window):
                chunk = batch[start:start + window]
                if not quiet:
                    self._send_window(chunk, timeout)
                for n, item in enumerate(chunk):
                    try:
                        answers.append(self._batch_answer(item, timeout, quiet))
                    except TmclStatusError as exc:
                        if first is None:
                            first, exc.index = exc, len(answers)
                        answers.append(None)
                    except (TmclTimeout, TmclProtocolError):
                        for rest in chunk[n + 1:]:  # sent, their replies still on the way
                            self._mark_lost(rest.request if isinstance(rest, _Plain) else rest)
                        raise
        if first is not None:
            first.answers = list(answers)
            raise first
        return answers

    def _batch_answer(self, item: _Plain | Request, timeout: float, alone: bool) -> Answer:
        """The answer to a request of a batch: sent with its window, or now when `alone`."""
        if alone:
            return self._ask(item, timeout) if isinstance(item, _Plain) else self._request_alone(item, timeout)
        if isinstance(item, _Plain):
            return self._read_plain(item, timeout, None)
        return self._read_answer(item, timeout)

    def _request_alone(self, req: Request, timeout: float) -> Answer:
        self._send(req, timeout)
        return self._read_answer(req, timeout)

    def _send_window(self, chunk: list[_Plain | Request], timeout: float) -> None:
        """Send a window of requests. Replies the transport has at hand at once
        (`Transport.exchange_many`; never for a window with a special reply) are held, in order,
        in front of the bytes still to receive."""
        if self._dirty or self._lost:
            head = chunk[0]
            self._in_step(head.request if isinstance(head, _Plain) else head, timeout)
        frames = [item.frame if isinstance(item, _Plain) else self._wire(item) for item in chunk]
        if all(isinstance(item, _Plain) for item in chunk):
            replies = self.transport.exchange_many(frames)
            if replies is not None:
                self._held += b"".join(replies)
        else:
            self.transport.send_many(frames)

    def _prepare_many(self, requests: Sequence[tuple[int, int, int, int]], address: int | None,
                      timeout: float | None) -> tuple[list[_Plain | Request], float]:
        """The checked requests (`_Plain`, or the `Request` of a special reply) and the time-out per reply."""
        if isinstance(requests, (str, bytes)) or not isinstance(requests, Sequence):
            raise TmclTypeError("requests must be a sequence of (command, type, motor, value) tuples, "
                                f"got {type(requests).__name__}")
        if len(requests) > MAX_BATCH:
            raise TmclBatchError(f"a batch takes at most {MAX_BATCH} requests, got {len(requests)}; "
                                 "split it into several request_many calls")
        timeout = self.timeout if timeout is None else check_timeout(timeout)
        self._check_reachable(address)
        target = self.address if address is None else address
        kept = self._plain
        batch: list[_Plain | Request] = []
        for index, item in enumerate(requests):
            if not (item.__class__ is tuple and len(item) == 4) and (
                    isinstance(item, (str, bytes)) or not isinstance(item, Sequence) or len(item) != 4):
                raise TmclTypeError(f"requests[{index}] must be a (command, type, motor, value) tuple, "
                                    f"got {item!r}")
            command, type_, motor, value = item
            if target.__class__ is command.__class__ is type_.__class__ is motor.__class__ \
                    is value.__class__ is int:
                plain = kept.get((target, command, type_, motor, value))
                if plain is not None:
                    batch.append(plain)
                    continue
            try:
                batch.append(self._check(command, type_, motor, value, address, timeout)[0])
            except TmclValueError as exc:
                raise TmclValueError(f"requests[{index}]: {exc}") from None
            except TmclTypeError as exc:
                raise TmclTypeError(f"requests[{index}]: {exc}") from None
        return batch, timeout

    def _read_answer(self, req: Request, timeout: float) -> Answer:
        """The answer to a request already sent, as `request` reads it."""
        if req.command in UNANSWERED:
            return None
        if is_version_request(req.command, req.type):
            return self._read_version(req, timeout)
        if req.command == READ_PROGRAM_MEMORY:
            return self._read_memory(req, timeout)
        return self._read_reply(req, timeout)

    def _prepare(self, command: int, type: int, motor: int, value: int, address: int | None,
                 timeout: float | None) -> tuple[Request, float]:
        """The checked request and the time-out to wait for its reply."""
        self._check_reachable(address)
        req = Request(_check_byte("address", self.address if address is None else address),
                      _check_byte("command", command), _check_byte("type", type),
                      _check_byte("motor", motor), _check_value(value))
        return req, self.timeout if timeout is None else check_timeout(timeout)

    def _check_reachable(self, address: int | None) -> None:
        """On CAN the connection's CAN ID selects the module: other addresses cannot be reached."""
        if address is not None and address != self.address and self.transport.frame_format == "can":
            raise TmclAddressError(
                f"module address {address}: a CAN connection reaches only the module of its CAN ID "
                f"({getattr(self.transport, 'can_id', '?')}, address {self.address} here); the address "
                "byte is not sent on CAN (manual 3.1). Open can://...?id=N for another module")

    def send_raw(self, frame: bytes, *, timeout: float | None = None) -> Answer:
        """Send a ready-made 9-byte request frame (its checksum is not checked) and return the reply."""
        try:
            req = Request.decode(bytes(frame), verify=False)
        except (FrameError, TypeError, ValueError) as exc:
            raise TmclValueError(f"not a 9-byte request frame: {exc}") from None
        return self.request(req.command, req.type, req.motor, req.value, address=req.address,
                            timeout=timeout)

    def _reset_input(self) -> None:
        """Discard what is left of a lost or garbled reply before the next request."""
        self.transport.reset_input()
        self._held.clear()
        self._dirty = False

    def _wire(self, req: Request) -> bytes:
        """`req` as sent: nine bytes, or eight on CAN, where the CAN ID carries the module address."""
        data = req.encode()
        return data[1:] if self._can else data

    def _send(self, req: Request, timeout: float) -> None:
        if self._dirty or self._lost:
            self._in_step(req, timeout)
        self.transport.send(self._wire(req))

    def _remaining(self, deadline: float) -> float:
        return max(0.0, deadline - self.transport.monotonic())

    def _recv(self, n: int, deadline: float) -> bytes:
        """`n` reply bytes: those held (`_read_plain`) first, then from the transport."""
        held = self._held
        try:
            if not held:
                return self.transport.recv(n, self._remaining(deadline))
            if len(held) >= n:
                out = bytes(held[:n])
                del held[:n]
                return out
            out = bytes(held) + self.transport.recv(n - len(held), self._remaining(deadline))
            held.clear()
            return out
        except TmclTimeout:
            self._dirty = True
            raise

    def _read_frame(self, deadline: float, req: Request | None = None) -> Reply:
        """Read one reply frame, re-synchronising byte by byte past garbage on serial links; a
        garbled frame is a TmclChecksumError naming `req` (TmclProtocolError without one). A good
        frame found only a whole frame or more further on follows a garbled reply (a window of
        replies): the error names `req`, and that frame is left to be read next."""
        if self._can:
            b = self._recv(CAN_REPLY_LEN, deadline)
            return Reply(self.host_address, b[0], b[1], b[2], _VALUE.unpack_from(b, 3)[0])
        buf = self._recv(FRAME_LEN, deadline)
        if checksum_ok(buf):
            return _new_tuple(Reply, _BODY.unpack_from(buf))
        first_bad, skipped = buf, 0
        while not checksum_ok(buf):
            try:
                buf = buf[1:] + self._recv(1, deadline)
            except TmclTimeout:
                if req is not None:
                    raise TmclChecksumError(req, first_bad) from None
                raise TmclProtocolError(f"reply with wrong checksum: {first_bad.hex(' ')}") from None
            skipped += 1
        if skipped >= FRAME_LEN and req is not None:
            self._held[:0] = buf
            raise TmclChecksumError(req, first_bad)
        return _new_tuple(Reply, _BODY.unpack_from(buf))

    def _no_reply(self, req: Request, timeout: float) -> TmclTimeout:
        self._mark_lost(req)
        return TmclTimeout(f"no reply from module {req.address} to {describe_request(req)} "
                           f"within {timeout:g} s")

    def _next_frame(self, req: Request, deadline: float, timeout: float) -> Reply:
        """The next frame that is not a command-138 event, or TmclTimeout naming the request."""
        while True:
            try:
                reply = self._read_frame(deadline, req)
            except TmclTimeout:
                raise self._no_reply(req, timeout) from None
            except TmclChecksumError:
                self._mark_lost(req)
                raise
            if not self._take_event(reply):
                return reply

    def _same_module(self, reply: Reply, req: Request) -> bool:
        # On CAN the reply ID already names the module; its address byte is not compared.
        return self._can or reply.module_address == req.address

    def _read_reply(self, req: Request, timeout: float, deadline: float | None = None) -> Reply:
        """The reply of `req`'s module and command: events in between are kept, other replies
        counted in `stray_replies`; an error status raises `TmclStatusError`. `deadline` (on the
        transport's clock) is `timeout` from now unless given."""
        if deadline is None:
            deadline = self.transport.monotonic() + timeout
        while True:
            reply = self._next_frame(req, deadline, timeout)
            if not self._same_module(reply, req) or reply.command != req.command:
                self.stray_replies += 1
                continue
            if not is_success(reply.status):
                raise TmclStatusError(reply.status, req, reply)
            return reply

    def _read_memory(self, req: Request, timeout: float) -> MemoryReply:
        """Command 134: the stored instruction in place of module address, status, command and
        value, with a normal checksum (docs/assumptions.md). A normal frame with command 134 and
        an error status is the module refusing the request."""
        reply = self._next_frame(req, self.transport.monotonic() + timeout, timeout)
        if reply.command == READ_PROGRAM_MEMORY and self._same_module(reply, req) and not is_success(reply.status):
            raise TmclStatusError(reply.status, req, reply)
        return MemoryReply(reply.reply_address, reply.module_address, reply.status, reply.command, reply.value)

    def _read_version(self, req: Request, timeout: float) -> VersionReply:
        deadline = self.transport.monotonic() + timeout
        can = self.transport.frame_format == "can"
        while True:
            try:
                buf = self._recv(CAN_VERSION_LEN if can else FRAME_LEN, deadline)
            except TmclTimeout:
                raise self._no_reply(req, timeout) from None
            if not can and checksum_ok(buf) and buf[3] & 0x80:
                # A normal frame (command byte >= 128 is never an ASCII character).
                reply = Reply.decode(buf)
                if self._take_event(reply):
                    continue
                if reply.module_address == req.address and reply.command == req.command:
                    if not is_success(reply.status):
                        raise TmclStatusError(reply.status, req, reply)
                self.stray_replies += 1
                continue
            text = buf if can else buf[1:]
            if not all(32 <= c < 127 for c in text):
                self._mark_lost(req)
                raise TmclProtocolError(f"not a version string reply: {buf.hex(' ')}")
            return VersionReply(self.host_address if can else buf[0], req.address, text.decode("ascii"))

    # ------------------------------------------------------------------ events (command 138)

    def _event_key(self, address: int) -> int:
        # A CAN transport talks to one module ID: its events all belong to that module.
        return -1 if self.transport.frame_format == "can" else address

    def _take_event(self, reply: Reply) -> bool:
        if reply.status == Status.POSITION_REACHED_EVENT and reply.command == REQUEST_TARGET_REACHED_EVENT:
            key = self._event_key(reply.module_address)
            self._events[key] = self._events.get(key, 0) | (reply.value & 0xFFFFFFFF)
            return True
        return False

    def pending_events(self, address: int | None = None) -> int:
        """Motor bit mask of "position reached" replies received and not yet consumed."""
        return self._events.get(self._event_key(self.address if address is None else address), 0)

    def clear_events(self, address: int | None = None) -> None:
        with self._lock:
            if address is None:
                self._events.clear()
            else:
                self._events.pop(self._event_key(address), None)

    def wait_position_reached(self, mask: int, timeout: float | None = None, *,
                              address: int | None = None) -> int:
        """Wait for the "target position reached" replies of command 138 (manual 3.6.35)
        until every motor bit of `mask` has been reported; consume and return those bits.

        Request the event first (command 138, e.g. `Module.request_position_reached_event`).
        """
        check_int(mask, "motor mask")
        if not 0 < mask <= 0xFFFFFFFF:
            raise TmclValueError(f"motor mask must be a non-zero 32-bit bit vector, got {mask!r}")
        address = self.address if address is None else _check_byte("address", address)
        key = self._event_key(address)
        timeout = self.timeout if timeout is None else check_timeout(timeout)
        deadline = self.transport.monotonic() + timeout
        while True:
            with self._lock:
                got = self._events.get(key, 0)
                if got & mask == mask:
                    self._events[key] = got & ~mask
                    return mask
                left = self._remaining(deadline)
                if left <= 0:
                    raise TmclTimeout(f"module {address}: no position reached event for motor mask "
                                      f"{mask & ~got:#x} within {timeout:g} s")
                before = self.transport.monotonic()
                try:
                    frame = self._read_frame(before + min(left, _WAIT_SLICE))
                except TmclTimeout:
                    self._dirty = False  # nothing was lost: we were only listening
                    if self.transport.monotonic() <= before:  # a clock that does not run: give up
                        deadline = before
                    continue
                if not self._take_event(frame):
                    self.stray_replies += 1

    # ------------------------------------------------------------------ misc

    def module(self, address: int | None = None,
               profile: ModuleProfile | str | None = None) -> Module:
        """A `Module` at `address` on this client's bus (several modules may share one client)."""
        from .module import Module

        self._check_reachable(address)
        return Module(self, address, profile)

    def sleep(self, seconds: float) -> None:
        """Let `seconds` (finite, >= 0) pass on the transport's clock (virtual time for in-process
        modules)."""
        self.transport.sleep(check_seconds(seconds))

    def close(self) -> None:
        self.transport.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
