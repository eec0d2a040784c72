"""The ASCII interface line format (PD28-1021 manual 3.4, PD86-1180 manual 4.5). Pure codec, no I/O.

Entering: binary command 139 switches the module to ASCII mode. Leaving: the command ``BIN``.

Command line (3.4.2): the address character first (A for module address 1, B for 2, ...), optional
spaces, the command with its parameters as in the TMCL-IDE, then <CR>. Examples from the manual::

    AMVP ABS, 1, 50000
    A MVP ABS, 1, 50000
    AROL 2, 500
    A MST 1
    ABIN

Reply (3.4.3): host address character, module address character, status code and return value as
decimal numbers, then <CR>: after ``AGAP 0, 1`` the reply is ``BA 100 -5000`` (host address 2,
module address 1, actual position -5000).

Only ROL, ROR, MST, MVP, SAP, GAP, STAP, RSAP, SGP, GGP, STGP, RSGP, RFS, SIO, GIO, SCO, GCO, CCO
and UF0..UF7 are accepted, plus the ASCII-only commands BIN (back to binary mode), RUN (start the
TMCL program) and STOP (stop the running TMCL program).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from enum import Enum

from ..limits import LiteralTooLong, check_literal
from .frame import Request, to_int32
from .opcodes import (
    ENTER_ASCII_MODE,
    MOTOR,
    RUN_APPLICATION,
    STOP_APPLICATION,
    TYPE,
    VALUE,
    Command,
    by_mnemonic,
    lookup_symbol,
    parse_number,
)
from .status import Status

CR = "\r"
BIN = "BIN"
RUN = "RUN"
STOP = "STOP"
ENTER_COMMAND = ENTER_ASCII_MODE  # binary command 139 enters ASCII mode

ASCII_COMMANDS = frozenset({
    "ROL", "ROR", "MST", "MVP", "SAP", "GAP", "STAP", "RSAP", "SGP", "GGP", "STGP", "RSGP", "RFS",
    "SIO", "GIO", "SCO", "GCO", "CCO", *(f"UF{i}" for i in range(8)),
})

_MNEMONIC = re.compile(r"\s*([A-Za-z]+[0-9]?)(.*)\Z", re.S)
_REPLY = re.compile(r"\s*([A-Za-z])\s*([A-Za-z])\s+([+-]?[0-9]+)\s+([+\-\u2212\u2013]?\s*[0-9]+)\s*\Z")


class AsciiError(ValueError):
    """A malformed ASCII command or reply line. `status` is the TMCL status code it maps to."""

    def __init__(self, message: str, status: int = Status.INVALID_COMMAND):
        super().__init__(message)
        self.status = int(status)


class EchoMode(Enum):
    """Echo behaviour chosen by bits 4 and 5 of global parameter 67 (3.4.4)."""

    CHARACTER = "character"  # both bits clear: every character is echoed
    LINE = "line"            # bit 4 set: the whole line is echoed after <CR>
    NONE = "none"            # bit 5 set: no echo, only the reply


def echo_mode(gp67: int) -> EchoMode:
    bit4, bit5 = bool(gp67 & 0x10), bool(gp67 & 0x20)
    if bit4 and not bit5:
        return EchoMode.LINE
    if bit5 and not bit4:
        return EchoMode.NONE
    return EchoMode.CHARACTER


def starts_in_ascii(gp67: int) -> bool:
    """Bit 0 of global parameter 67: start up in ASCII mode (3.4.4)."""
    return bool(gp67 & 1)


def address_letter(address: int) -> str:
    """A for address 1, B for 2, ... Z for 26."""
    if not 1 <= address <= 26:
        raise AsciiError(f"address {address} has no ASCII address character (1..26)")
    return chr(ord("A") + address - 1)


def letter_address(letter: str) -> int:
    """Module address of an address character (case-insensitive)."""
    if len(letter) != 1 or not letter.isascii() or not letter.isalpha():
        raise AsciiError(f"address character must be a letter A..Z, got {letter!r}")
    return ord(letter.upper()) - ord("A") + 1


@dataclass(frozen=True, slots=True)
class AsciiCommand:
    """A parsed command line. `command` is None for BIN, which has no binary form."""

    address: int
    mnemonic: str
    command: int | None
    type: int = 0
    motor: int = 0
    value: int = 0

    @property
    def is_bin(self) -> bool:
        return self.mnemonic == BIN

    def to_request(self) -> Request:
        """The equivalent binary request (RUN -> 129, STOP -> 128); AsciiError for BIN."""
        if self.command is None:
            raise AsciiError("BIN has no binary representation")
        return Request(self.address, self.command, self.type, self.motor, self.value)


@dataclass(frozen=True, slots=True)
class AsciiReply:
    host_address: int
    module_address: int
    status: int
    value: int


def parse_command(line: str) -> AsciiCommand:
    """Parse one command line (with or without its trailing <CR>)."""
    address, mnemonic, operands = _split_line(line)
    if mnemonic in (BIN, STOP, RUN):
        return _ascii_only_command(address, mnemonic, operands)
    if mnemonic not in ASCII_COMMANDS:
        raise AsciiError(f"command {mnemonic} cannot be used in ASCII mode")
    cmd = by_mnemonic(mnemonic)
    form = cmd.form_for(len(operands))
    if form is None or any(not p for p in operands):
        raise AsciiError(f"wrong operands for {mnemonic}; expected {cmd.usage()}", Status.WRONG_TYPE)
    fields = {TYPE: 0, MOTOR: 0, VALUE: 0}
    for name, text in zip(form, operands, strict=True):
        fields[name] = _operand(cmd, mnemonic, name, text)
    return AsciiCommand(address, mnemonic, cmd.number, fields[TYPE], fields[MOTOR], fields[VALUE])


def _split_line(line: str) -> tuple[int, str, list[str]]:
    """Address character, command (upper case) and comma-separated operands of a line (3.4.2)."""
    text = line.rstrip("\r\n")
    stripped = text.lstrip()
    if not stripped:
        raise AsciiError("empty command line")
    address = letter_address(stripped[0])
    m = _MNEMONIC.match(stripped[1:])
    if not m:
        raise AsciiError(f"missing command after address character in {text!r}")
    mnemonic, rest = m.group(1).upper(), m.group(2).strip()
    if m.group(2)[:1] not in ("", " ", "\t"):
        raise AsciiError(f"expected a space after {mnemonic} in {text!r}")
    return address, mnemonic, [p.strip() for p in rest.split(",")] if rest else []


def _ascii_only_command(address: int, mnemonic: str, operands: list[str]) -> AsciiCommand:
    """BIN and STOP (no operands) and RUN [start address]: the commands of ASCII mode only."""
    if mnemonic in (BIN, STOP):
        if operands:
            raise AsciiError(f"{mnemonic} takes no operands")
        return AsciiCommand(address, mnemonic, None if mnemonic == BIN else STOP_APPLICATION)
    if not operands:
        return AsciiCommand(address, RUN, RUN_APPLICATION, 0, 0, 0)
    if len(operands) == 1:
        return AsciiCommand(address, RUN, RUN_APPLICATION, 1, 0, _number(operands[0], "address"))
    raise AsciiError("RUN takes at most one operand (start address)")


def _operand(cmd: Command, mnemonic: str, name: str, text: str) -> int:
    """One operand: a type (a symbol such as ABS, or a number 0..255), a motor/bank (0..255) or a
    value (32 bit). Out of range: "wrong type" for a type, "invalid value" otherwise."""
    num = lookup_symbol(cmd, text) if name == TYPE else None
    if num is None and name == TYPE and _number_or_none(text, name) is None:
        raise AsciiError(f"unknown type {text!r} for {mnemonic}; expected {cmd.usage()}",
                         Status.WRONG_TYPE)
    if num is None:
        num = _number(text, name)
    if name in (TYPE, MOTOR) and not 0 <= num <= 255:
        raise AsciiError(f"{name} of {mnemonic} must be 0..255, got {num}",
                         Status.WRONG_TYPE if name == TYPE else Status.INVALID_VALUE)
    return num


def _number_or_none(text: str, what: str) -> int | None:
    try:
        return parse_number(text)
    except LiteralTooLong as exc:
        raise AsciiError(f"{what}: {exc}", Status.INVALID_VALUE) from None


def _number(text: str, what: str) -> int:
    num = _number_or_none(text, what)
    if num is None:
        raise AsciiError(f"{what} must be a number, got {text!r}", Status.INVALID_VALUE)
    if not -(1 << 31) <= num <= 0xFFFFFFFF:
        raise AsciiError(f"{what} out of 32-bit range: {text}", Status.INVALID_VALUE)
    return to_int32(num)


def format_command(address: int, mnemonic: str, *operands: str | int) -> str:
    """A command line without <CR>: format_command(1, "MVP", "ABS", 1, 50000) -> 'AMVP ABS, 1, 50000'."""
    ops = ", ".join(str(o) for o in operands)
    return f"{address_letter(address)}{mnemonic.upper()}{' ' + ops if ops else ''}"


def format_reply(host_address: int, module_address: int, status: int, value: int) -> str:
    """A reply line without <CR>: format_reply(2, 1, 100, -5000) -> 'BA 100 -5000'."""
    return f"{address_letter(host_address)}{address_letter(module_address)} {int(status)} {to_int32(value)}"


def encode_reply(host_address: int, module_address: int, status: int, value: int) -> bytes:
    """The reply line as sent: ASCII text terminated by <CR>."""
    return (format_reply(host_address, module_address, status, value) + CR).encode("ascii")


def parse_reply(line: str) -> AsciiReply:
    """Parse 'BA 100 -5000' (the manual's en dash or minus sign is accepted as '-')."""
    m = _REPLY.match(line.rstrip("\r\n"))
    if not m:
        raise AsciiError(f"not an ASCII reply line: {line!r}")
    value_text = m.group(4).replace("\u2212", "-").replace("\u2013", "-").replace(" ", "")
    try:
        check_literal(m.group(3).lstrip("+-"))
        check_literal(value_text.lstrip("+-"))
    except LiteralTooLong as exc:
        raise AsciiError(f"not an ASCII reply line: {exc}") from None
    return AsciiReply(letter_address(m.group(1)), letter_address(m.group(2)), int(m.group(3)),
                      to_int32(int(value_text)))
