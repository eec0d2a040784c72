"""Special replies that do not follow the 9-byte reply format (or that give it a special meaning).

- Command 136 type 0 (get firmware version as a string), PD86-1180 manual 4.6.39 "Special reply
  format of command 136": byte 1 host address, bytes 2..9 the version string (8 characters),
  "There is no checksum in this reply format!"
- Command 138 (request target position reached event), TMCM-6212 manual 3.6.35: an immediate reply
  (status 100) and, when the motors in the bit mask have reached their targets, an additional reply
  with status 128 and the motor bit mask in the value field.
- Command 134 (read program memory), TMCM-6212 manual 3.6.36: "special reply format". The manuals
  do not print it; public clients read it as the stored command's seven bytes in place of module
  address, status, command and value, followed by the usual checksum (docs/assumptions.md).
"""
from __future__ import annotations

from dataclasses import dataclass

from .frame import FrameError, Reply, decode_frame, encode_frame
from .opcodes import GET_FIRMWARE_VERSION, REQUEST_TARGET_REACHED_EVENT
from .status import Status

VERSION_LEN = 8
VERSION_REPLY_LEN = 1 + VERSION_LEN


# --- 136 type 0: version string --------------------------------------------------------------

def encode_version_string_reply(reply_address: int, version: str) -> bytes:
    """Reply address + 8 ASCII characters, no checksum (PD86-1180 4.6.39)."""
    if not 0 <= reply_address <= 0xFF:
        raise FrameError(f"reply address must be 0..255, got {reply_address}")
    try:
        raw = version.encode("ascii")
    except UnicodeEncodeError:
        raise FrameError(f"version string must be ASCII, got {version!r}") from None
    if len(raw) != VERSION_LEN:
        raise FrameError(f"version string must be {VERSION_LEN} characters, got {len(raw)} ({version!r})")
    return bytes([reply_address]) + raw


def decode_version_string_reply(data: bytes) -> tuple[int, str]:
    """(reply address, version string) of a 9-byte command 136 type 0 reply."""
    data = bytes(data)
    if len(data) != VERSION_REPLY_LEN:
        raise FrameError(f"version string reply must be {VERSION_REPLY_LEN} bytes, got {len(data)}")
    try:
        return data[0], data[1:].decode("ascii")
    except UnicodeDecodeError:
        raise FrameError("version string reply is not ASCII") from None


def is_version_request(command: int, type: int) -> bool:
    """True for the request whose reply is the special string format (136 type 0)."""
    return command == GET_FIRMWARE_VERSION and type == 0


# --- 138: target position reached event ------------------------------------------------------

def target_reached_event(reply_address: int, module_address: int, motor_mask: int) -> Reply:
    """The additional reply sent when the motors have reached their target (status 128)."""
    return Reply(reply_address, module_address, Status.POSITION_REACHED_EVENT,
                 REQUEST_TARGET_REACHED_EVENT, motor_mask)


def is_target_reached_event(reply: Reply) -> bool:
    return reply.status == Status.POSITION_REACHED_EVENT and reply.command == REQUEST_TARGET_REACHED_EVENT


def motor_mask(motors: list[int] | tuple[int, ...]) -> int:
    """Bit vector of command 138: bit n stands for motor n (TMCM-6212 3.6.35)."""
    mask = 0
    for m in motors:
        if not 0 <= m <= 31:
            raise ValueError(f"motor number must be 0..31, got {m}")
        mask |= 1 << m
    return mask


def motors_in_mask(mask: int) -> list[int]:
    """Motor numbers whose bit is set in a command 138 bit vector."""
    mask &= 0xFFFFFFFF
    return [m for m in range(32) if mask >> m & 1]


# --- 134: read program memory ----------------------------------------------------------------

@dataclass(frozen=True, slots=True)
class MemoryReply:
    """Reply of command 134: the stored instruction at the requested address."""

    reply_address: int
    command: int
    type: int
    motor: int
    value: int

    def encode(self) -> bytes:
        return encode_frame(self.reply_address, self.command, self.type, self.motor, self.value)

    @classmethod
    def decode(cls, data: bytes, *, verify: bool = True) -> MemoryReply:
        return cls(*decode_frame(data, verify=verify, what="memory reply"))
