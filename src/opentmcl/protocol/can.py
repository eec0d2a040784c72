"""TMCL over CAN: data payloads without address and checksum.

TMCM-6212 manual 3.1 (note): "When using the CAN interface, leave out the address byte and the
checksum byte. With CAN, the CAN-ID is used as the module address". 3.2 (note): the reply "does
not contain an address byte and a checksum byte. With CAN, the CAN-ID is used as the reply
address". PD86-1180 manual 4.2: "the first byte (reply address) and the last byte (checksum) are
left out" - so a reply payload is module address, status, command, value (7 bytes).

A request payload is 7 bytes: command, type, motor/bank, value (MSB first). Public clients
(PyTrinamic) send 8 bytes: the 9-byte serial frame without its address byte, i.e. with a trailing
checksum that the module ignores (docs/assumptions.md). Both lengths are accepted. PD86-1180 manual 4.6.39:
command 136 type 0 sent in an eight-byte frame is answered with eight bytes, so that all eight
characters of the version string fit.
"""
from __future__ import annotations

from dataclasses import dataclass

from .frame import FrameError, checksum, decode_frame, encode_frame, to_int32

REQUEST_LEN = 7
LONG_REQUEST_LEN = 8
REPLY_LEN = 7
VERSION_LEN = 8
MAX_STANDARD_ID = 0x7FF


class CanFrameError(FrameError):
    """A CAN payload that is not a well-formed TMCL request or reply."""


@dataclass(frozen=True, slots=True)
class CanRequest:
    """A TMCL request as carried in a CAN data field; `long` marks the 8-byte form."""

    command: int
    type: int
    motor: int
    value: int
    long: bool = False

    def encode(self, *, address: int | None = None) -> bytes:
        """7 bytes, or 8 when `long` (trailing checksum as PyTrinamic computes it over the
        serial frame including `address`, default 0)."""
        return encode_request(self.command, self.type, self.motor, self.value,
                              long=self.long, address=address)


@dataclass(frozen=True, slots=True)
class CanReply:
    """A TMCL reply payload: module address, status, command, value."""

    module_address: int
    status: int
    command: int
    value: int

    def encode(self) -> bytes:
        return encode_reply(self.module_address, self.status, self.command, self.value)


def _check_byte(name: str, v: int) -> int:
    if not isinstance(v, int) or not 0 <= v <= 0xFF:
        raise CanFrameError(f"{name} must be 0..255, got {v!r}")
    return v


def encode_request(command: int, type: int, motor: int, value: int, *,
                   long: bool = False, address: int | None = None) -> bytes:
    """CAN request payload: command, type, motor, value (MSB first) [+ checksum when `long`]:
    the 9-byte frame without its address byte (and without its checksum unless `long`)."""
    fields = _check_byte("command", command), _check_byte("type", type), _check_byte("motor", motor)
    value = to_int32(value)
    addr = 0 if address is None or not long else _check_byte("address", address)
    frame = encode_frame(addr, *fields, value)
    return frame[1:] if long else frame[1:REQUEST_LEN + 1]


def decode_request(data: bytes) -> CanRequest:
    """Decode a 7- or 8-byte request payload (the 8th byte, a checksum, is ignored)."""
    data = bytes(data)
    if len(data) not in (REQUEST_LEN, LONG_REQUEST_LEN):
        raise CanFrameError(f"CAN request must be {REQUEST_LEN} or {LONG_REQUEST_LEN} bytes, got {len(data)}")
    _, cmd, typ, motor, value = _fields(data)
    return CanRequest(cmd, typ, motor, value, long=len(data) == LONG_REQUEST_LEN)


def encode_reply(module_address: int, status: int, command: int, value: int) -> bytes:
    """CAN reply payload (7 bytes): module address, status, command, value (MSB first) - the serial
    reply without reply address and checksum."""
    fields = _check_byte("module address", module_address), _check_byte("status", status), _check_byte("command", command)
    return encode_frame(0, *fields, value)[1:REPLY_LEN + 1]


def decode_reply(data: bytes) -> CanReply:
    """Decode a 7-byte reply payload."""
    data = bytes(data)
    if len(data) != REPLY_LEN:
        raise CanFrameError(f"CAN reply must be {REPLY_LEN} bytes, got {len(data)}")
    _, module_address, status, command, value = _fields(data)
    return CanReply(module_address, status, command, value)


def _fields(payload: bytes) -> tuple[int, int, int, int, int]:
    """The frame fields of the first seven payload bytes, read as a 9-byte frame with an address
    byte 0 in front and its checksum after (manual 3.1 note: CAN leaves both out)."""
    body = bytes(1) + payload[:7]
    return decode_frame(body + bytes([checksum(body)]))


def encode_version_reply(version: str, *, long: bool = True) -> bytes:
    """Reply payload of command 136 type 0: the 8 version characters (PD86-1180 4.6.39).

    The serial reply is host address + 8 characters; on CAN the address is the CAN-ID, so the
    payload is the characters themselves: all 8 for an 8-byte request (`long`), else the first 7.
    """
    raw = _version_bytes(version)
    return raw if long else raw[:REQUEST_LEN]


def decode_version_reply(data: bytes) -> str:
    """The version characters of a 7- or 8-byte command 136 type 0 reply payload."""
    data = bytes(data)
    if len(data) not in (REQUEST_LEN, VERSION_LEN):
        raise CanFrameError(f"CAN version reply must be 7 or 8 bytes, got {len(data)}")
    try:
        return data.decode("ascii")
    except UnicodeDecodeError:
        raise CanFrameError("CAN version reply is not ASCII") from None


def _version_bytes(version: str) -> bytes:
    try:
        raw = version.encode("ascii")
    except UnicodeEncodeError:
        raise CanFrameError(f"version string must be ASCII, got {version!r}") from None
    if len(raw) != VERSION_LEN:
        raise CanFrameError(f"version string must be {VERSION_LEN} characters, got {len(raw)}")
    return raw


def check_can_id(can_id: int) -> int:
    """A standard (11-bit) CAN identifier as used for module and reply IDs (global parameters 70 and 71)."""
    if not isinstance(can_id, int) or not 0 <= can_id <= MAX_STANDARD_ID:
        raise CanFrameError(f"CAN ID must be 0..{MAX_STANDARD_ID}, got {can_id!r}")
    return can_id
