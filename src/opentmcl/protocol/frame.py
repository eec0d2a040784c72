"""Binary TMCL frames (TMCM-6212 manual 3.1, 3.1.1, 3.2).

A request on RS-232/RS-485/USB is nine bytes: module address, command, type,
motor/bank, value (signed 32 bit, MSB first), checksum (8-bit sum of the other
eight bytes). A reply is reply address, module address, status, command,
value, checksum.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass

FRAME_LEN = 9
_BODY = struct.Struct(">BBBBi")


class FrameError(ValueError):
    """A byte string that is not a well-formed TMCL frame."""


def checksum(data: bytes) -> int:
    """8-bit sum of all bytes (manual 3.1.1)."""
    return sum(data) & 0xFF


def to_int32(value: int) -> int:
    """Wrap any integer to signed 32-bit two's complement."""
    value &= 0xFFFFFFFF
    return value - 0x1_0000_0000 if value & 0x8000_0000 else value


@dataclass(frozen=True, slots=True)
class Request:
    address: int
    command: int
    type: int
    motor: int
    value: int

    def encode(self) -> bytes:
        body = _BODY.pack(self.address & 0xFF, self.command & 0xFF, self.type & 0xFF,
                          self.motor & 0xFF, to_int32(self.value))
        return body + bytes([checksum(body)])

    @classmethod
    def decode(cls, data: bytes, *, verify: bool = True) -> Request:
        if len(data) != FRAME_LEN:
            raise FrameError(f"request must be {FRAME_LEN} bytes, got {len(data)}")
        if verify and checksum(data[:8]) != data[8]:
            raise FrameError("wrong checksum")
        return cls(*_BODY.unpack_from(data))


@dataclass(frozen=True, slots=True)
class Reply:
    reply_address: int
    module_address: int
    status: int
    command: int
    value: int

    def encode(self) -> bytes:
        body = _BODY.pack(self.reply_address & 0xFF, self.module_address & 0xFF, self.status & 0xFF,
                          self.command & 0xFF, to_int32(self.value))
        return body + bytes([checksum(body)])

    @classmethod
    def decode(cls, data: bytes, *, verify: bool = True) -> Reply:
        if len(data) != FRAME_LEN:
            raise FrameError(f"reply must be {FRAME_LEN} bytes, got {len(data)}")
        if verify and checksum(data[:8]) != data[8]:
            raise FrameError("wrong checksum")
        return cls(*_BODY.unpack_from(data))
