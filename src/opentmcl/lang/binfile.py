"""TMCL-IDE binary program files: a plain sequence of 8-byte records, no header
(docs/tmcl-assembler.md "Binary file format").

Each record is one instruction: command, type, motor/bank, value (signed 32 bit, MSB first) and a
checksum, the 8-bit sum of the first seven bytes - the 9-byte frame of TMCM-6212 manual 3.1 without
its address byte.
"""
from __future__ import annotations

import os
import struct
from typing import NamedTuple

from ..atomicfile import write_atomic
from ..limits import IMAGE_MAX, InputTooLarge, read_bytes
from ..protocol.frame import checksum, to_int32

RECORD_LEN = 8
_BODY = struct.Struct(">BBBi")


class BinFileError(ValueError):
    """A byte string that is not a sequence of valid 8-byte program records."""


class Instruction(NamedTuple):
    """One TMCL instruction as stored in program memory."""

    command: int
    type: int = 0
    motor: int = 0
    value: int = 0

    def encode(self) -> bytes:
        """The 8-byte record: 7 bytes + checksum of those 7 bytes."""
        for name, v in (("command", self.command), ("type", self.type), ("motor", self.motor)):
            if not 0 <= v <= 0xFF:
                raise BinFileError(f"{name} must be 0..255, got {v}")
        body = _BODY.pack(self.command, self.type, self.motor, to_int32(self.value))
        return body + bytes([checksum(body)])


def encode(program: list[Instruction] | tuple[Instruction, ...]) -> bytes:
    """The binary file image of a program."""
    return b"".join(Instruction(*i).encode() for i in program)


def decode(data: bytes | bytearray | memoryview, *, verify: bool = True) -> list[Instruction]:
    """Instructions of a binary file image; BinFileError names the first bad record."""
    data = bytes(data)
    if len(data) % RECORD_LEN:
        raise BinFileError(f"length {len(data)} is not a multiple of {RECORD_LEN} bytes "
                           f"(record {len(data) // RECORD_LEN} is incomplete)")
    out = []
    for index in range(len(data) // RECORD_LEN):
        rec = data[index * RECORD_LEN:(index + 1) * RECORD_LEN]
        if verify and checksum(rec[:7]) != rec[7]:
            raise BinFileError(f"record {index} (byte offset {index * RECORD_LEN}): wrong checksum "
                               f"{rec[7]:02X}h, expected {checksum(rec[:7]):02X}h")
        out.append(Instruction(*_BODY.unpack_from(rec)))
    return out


def read(path: str | os.PathLike[str]) -> list[Instruction]:
    """The instructions of a binary file; BinFileError also for a file over IMAGE_MAX bytes."""
    try:
        return decode(read_bytes(path, IMAGE_MAX, "binary program image"))
    except InputTooLarge as exc:
        raise BinFileError(str(exc)) from None


def write(path: str | os.PathLike[str], program: list[Instruction] | tuple[Instruction, ...]) -> None:
    """Write atomically (temporary file, fsync, rename), so a killed process leaves no half file."""
    write_atomic(path, encode(program))
