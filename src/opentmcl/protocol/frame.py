"""Binary TMCL frames (TMCM-6212 manual 3.1, 3.1.1, 3.2).

A request on RS-232/RS-485/USB is nine bytes: module address, command, type,
motor/bank, value (signed 32 bit, MSB first), checksum (8-bit sum of the other
eight bytes). A reply is reply address, module address, status, command,
value, checksum.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import NamedTuple

FRAME_LEN = 9
_BODY = struct.Struct(">BBBBi")

Fields = tuple[int, int, int, int, int]
"""The five fields of a frame: four bytes and the signed 32-bit value."""


class FrameError(ValueError):
    """A byte string that is not a well-formed TMCL frame."""


def checksum(data: bytes) -> int:
    """8-bit sum of all bytes (manual 3.1.1)."""
    return sum(data) & 0xFF


def checksum_ok(frame: bytes) -> bool:
    """True when the ninth byte is the checksum of the first eight (manual 3.1.1)."""
    return checksum(frame[:8]) == frame[8]


def to_int32(value: int) -> int:
    """Wrap any integer to signed 32-bit two's complement."""
    value &= 0xFFFFFFFF
    return value - 0x1_0000_0000 if value & 0x8000_0000 else value


def encode_frame(b1: int, b2: int, b3: int, b4: int, value: int) -> bytes:
    """The nine bytes of a frame (manual 3.1 "binary command format", 3.2 "reply format"): four
    bytes (each taken modulo 256), the value (wrapped to 32 bits, MSB first) and the checksum."""
    body = _BODY.pack(b1 & 0xFF, b2 & 0xFF, b3 & 0xFF, b4 & 0xFF, to_int32(value))
    return body + bytes([checksum(body)])


def decode_frame(data: bytes, *, verify: bool = True, what: str = "frame") -> Fields:
    """The five fields of a nine-byte frame; FrameError names `what` when the length is wrong and
    reports a wrong checksum when `verify`."""
    if len(data) != FRAME_LEN:
        raise FrameError(f"{what} must be {FRAME_LEN} bytes, got {len(data)}")
    if verify and checksum(data[:8]) != data[8]:
        raise FrameError("wrong checksum")
    return _BODY.unpack_from(data)  # ">BBBBi": five ints


@dataclass(frozen=True, slots=True)
class Request:
    """Module address, command, type, motor/bank, value (manual 3.1)."""

    address: int
    command: int
    type: int
    motor: int
    value: int

    def encode(self) -> bytes:
        return encode_frame(self.address, self.command, self.type, self.motor, self.value)

    @classmethod
    def decode(cls, data: bytes, *, verify: bool = True) -> Request:
        return cls(*decode_frame(data, verify=verify, what="request"))


class Reply(NamedTuple):
    """Reply address, module address, status, command, value (manual 3.2)."""

    reply_address: int
    module_address: int
    status: int
    command: int
    value: int

    def encode(self) -> bytes:
        return encode_frame(self.reply_address, self.module_address, self.status, self.command, self.value)

    @classmethod
    def decode(cls, data: bytes, *, verify: bool = True) -> Reply:
        return cls(*decode_frame(data, verify=verify, what="reply"))
