"""Which instructions a module cannot execute, read from its profile (docs/tmcl-assembler.md
"Checking against a module"; docs/profiles.md).

Everything module-specific comes from the profile: its opcodes, number of axes, axis and global
parameter tables (with their access letters), user variables, I/O ports, coordinates and
interrupts. What each command's fields name is the same on every module and is data of the
command set (`Command.meanings` in protocol/opcodes.py, from TMCM-6212 manual 3.6.1-3.6.33,
PD86-1180 manual 4.6): e.g. SAP's type is an axis parameter and its motor field an axis; SGP's
type is a global parameter of the bank in its motor field; SIO's type is a port. A finding names
the field at fault, so the assembler can point at that operand.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..protocol import opcodes
from ..protocol.opcodes import (
    AXIS,
    AXIS_PARAMETER,
    COORDINATE,
    GLOBAL_PARAMETER,
    INTERRUPT,
    MOTOR,
    PORT,
    Meaning,
)
from .binfile import Instruction

if TYPE_CHECKING:
    from ..modules.profile import ModuleProfile

USER_BANK = 2          # SGP/GGP bank 2: the user variables (TMCM-6212 3.6.7)
ALL = 255              # EI/DI 255: interrupt processing as a whole (TMCM-6212 3.6.30-3.6.31)
_ACCESS_WORD = {"W": "written", "R": "read", "E": "stored to or restored from EEPROM"}


@dataclass(frozen=True)
class Finding:
    """Why `module` cannot execute an instruction; `field` is command, type, motor or value."""

    field: str
    message: str


def direct_only(ins: Instruction) -> Finding | None:
    """A command of direct mode only in a program, on every module: 138 ("This instruction can only
    be used in direct mode", TMCM-6212 3.6.35) and the control commands ("can only be used in direct
    mode and not in a standalone program", 3.6.36). The module skips it (status 6)."""
    cmd = opcodes.COMMANDS.get(ins.command)
    if cmd is None or cmd.program:
        return None
    name = cmd.mnemonic or f"command {ins.command}"
    return Finding("command", f"{name} can only be used in direct mode: in a program the module skips it (status 6)")


def check(ins: Instruction, profile: ModuleProfile) -> list[Finding]:
    """Every reason why `profile`'s firmware would refuse `ins` (empty: it can execute it)."""
    cmd = opcodes.COMMANDS.get(ins.command)
    name = cmd.mnemonic if cmd is not None and cmd.mnemonic else f"command {ins.command}"
    if ins.command not in profile.opcodes:
        return [Finding("command", f"{name} (command {ins.command}) is not available on {profile.name}")]
    only = direct_only(ins)
    if only is not None:
        return [only]
    out: list[Finding] = []
    for names, rule in _RULES:
        meaning = cmd.naming(names, ins.type) if cmd is not None else None
        if meaning is not None:
            rule(ins, meaning, name, profile, out)
    return out


def _number(ins: Instruction, meaning: Meaning) -> int:
    """The field of `ins` that `meaning` is about."""
    value: int = getattr(ins, meaning.field)
    return value


def _axes(profile: ModuleProfile) -> str:
    return "motor 0 only" if profile.axes == 1 else f"motors 0..{profile.axes - 1}"


def _motor(ins: Instruction, meaning: Meaning, name: str, profile: ModuleProfile, out: list[Finding]) -> None:
    motor = _number(ins, meaning)
    if motor != meaning.special and motor >= profile.axes:
        out.append(Finding(meaning.field, f"{name}: motor {motor} does not exist on {profile.name} "
                                          f"({_axes(profile)})"))


def _access(p_access: str, need: str) -> bool:
    return need in p_access or (need == "E" and "A" in p_access)


def _axis_param(ins: Instruction, meaning: Meaning, name: str, profile: ModuleProfile,
                out: list[Finding]) -> None:
    number, need = _number(ins, meaning), meaning.access
    p = profile.axis_parameters.get(number)
    if p is None:
        out.append(Finding(meaning.field, f"{name}: {profile.name} has no axis parameter {number}"))
    elif not _access(p.access, need):
        out.append(Finding(meaning.field, f"{name}: axis parameter {number} ({p.name}) of {profile.name} "
                                          f"cannot be {_ACCESS_WORD[need]}"))


def _global_param(ins: Instruction, meaning: Meaning, name: str, profile: ModuleProfile,
                  out: list[Finding]) -> None:
    bank, number, need = ins.motor, _number(ins, meaning), meaning.access
    if bank == USER_BANK:
        size = profile.storable_user_variables if need == "E" else profile.user_variables
        if number >= size:
            what = "storable user variables" if need == "E" else "user variables"
            out.append(Finding(meaning.field, f"{name}: {profile.name} has {size} {what} (0..{size - 1}), "
                                              f"not {number}"))
        return
    if bank not in profile.global_banks:  # bank 2 returned above
        banks = sorted(profile.global_banks)
        out.append(Finding(MOTOR, f"{name}: {profile.name} has no global parameter bank {bank} "
                                  f"(banks {', '.join(map(str, banks))})"))
        return
    p = profile.global_parameters.get((bank, number))
    if p is None:
        out.append(Finding(meaning.field, f"{name}: {profile.name} has no global parameter {number} "
                                          f"in bank {bank}"))
    elif not _access(p.access, need):
        out.append(Finding(meaning.field, f"{name}: global parameter {number} ({p.name}) of {profile.name} "
                                          f"cannot be {_ACCESS_WORD[need]}"))


def _io(ins: Instruction, meaning: Meaning, name: str, profile: ModuleProfile, out: list[Finding]) -> None:
    port, bank = _number(ins, meaning), ins.motor
    if not any(b == bank for b, _ in profile.io):
        out.append(Finding(MOTOR, f"{name}: {profile.name} has no I/O bank {bank}"))
        return
    pullups = profile.extra.get("pullups")
    if port == meaning.special or (pullups and (bank, port) == (pullups["bank"], pullups["port"])):
        return
    p = profile.io.get((bank, port))
    if p is None:
        out.append(Finding(meaning.field, f"{name}: {profile.name} has no port {port} in I/O bank {bank}"))
    elif meaning.access == "W" and "W" not in p.access:
        out.append(Finding(meaning.field, f"{name}: port {port} in bank {bank} ({p.name}) of {profile.name} "
                                          "is an input"))


def _coordinate(ins: Instruction, meaning: Meaning, name: str, profile: ModuleProfile,
                out: list[Finding]) -> None:
    number = _number(ins, meaning)
    if not 0 <= number <= profile.coordinates:
        out.append(Finding(meaning.field, f"{name}: {profile.name} has coordinates 0..{profile.coordinates}, "
                                          f"not {number}"))


def _interrupt(ins: Instruction, meaning: Meaning, name: str, profile: ModuleProfile,
               out: list[Finding]) -> None:
    number = _number(ins, meaning)
    if number == meaning.special:  # EI/DI 255: all interrupts
        return
    if number == ALL:  # VECT 255 names no vector (3.6.32)
        out.append(Finding(meaning.field, f"{name}: 255 is not an interrupt vector (it switches all interrupts)"))
    elif number not in profile.interrupts:
        out.append(Finding(meaning.field, f"{name}: {profile.name} has no interrupt {number}"))


_Rule = Callable[[Instruction, Meaning, str, "ModuleProfile", list[Finding]], None]
_RULES: tuple[tuple[str, _Rule], ...] = (
    (AXIS, _motor), (AXIS_PARAMETER, _axis_param), (GLOBAL_PARAMETER, _global_param), (PORT, _io),
    (COORDINATE, _coordinate), (INTERRUPT, _interrupt),
)
"""What each kind of field is checked against, in the order findings are listed."""
