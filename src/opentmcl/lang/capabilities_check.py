"""Which instructions a module cannot execute, read from its profile (docs/tmcl-assembler.md
"Checking against a module"; docs/profiles.md).

Everything module-specific comes from the profile: its opcodes, number of axes, axis and global
parameter tables (with their access letters), user variables, I/O ports, coordinates and
interrupts. What is fixed here is the meaning of each command's fields, the same on every module
(TMCM-6212 manual 3.6.1-3.6.33, PD86-1180 manual 4.6): e.g. SAP's type is an axis parameter number
and its motor field an axis; SGP's motor field is a bank; SIO's type is a port and its motor field
a bank. A finding names the field at fault, so the assembler can point at that operand.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..protocol import opcodes
from .binfile import Instruction

if TYPE_CHECKING:
    from ..modules.profile import ModuleProfile

USER_BANK = 2          # SGP/GGP bank 2: the user variables (TMCM-6212 3.6.7)
ALL = 255              # SIO/GIO 255: all ports; EI/DI 255: interrupt processing as a whole;
                       # SCO/GCO motor 255: copy coordinates RAM <-> EEPROM (TMCM-6212 3.6.22-3.6.23)
_AXIS_MOTOR = frozenset({1, 2, 3, 4, 5, 6, 7, 8, 13, 30, 31, 32, 34, 39, 46, 50, 51})
_AXIS_PARAM = {5: "W", 34: "W", 6: "R", 7: "E", 8: "E"}   # SAP AAP write, GAP read, STAP RSAP store
_GLOBAL_PARAM = {9: "W", 35: "W", 10: "R", 11: "E", 12: "E"}
_COORDINATE = frozenset({30, 31, 32, 39})                 # SCO GCO CCO ACO: type = coordinate
_WAIT_ON_MOTOR = frozenset({1, 2, 3, 4})                  # WAIT POS, REFSW, LIMSW, RFS
_ACCESS_WORD = {"W": "written", "R": "read", "E": "stored to or restored from EEPROM"}


@dataclass(frozen=True)
class Finding:
    """Why `module` cannot execute an instruction; `field` is command, type, motor or value."""

    field: str
    message: str


def check(ins: Instruction, profile: ModuleProfile) -> list[Finding]:
    """Every reason why `profile`'s firmware would refuse `ins` (empty: it can execute it)."""
    cmd = opcodes.COMMANDS.get(ins.command)
    name = cmd.mnemonic if cmd is not None and cmd.mnemonic else f"command {ins.command}"
    if ins.command not in profile.opcodes:
        return [Finding("command", f"{name} (command {ins.command}) is not available on {profile.name}")]
    out: list[Finding] = []
    for rule in _RULES:
        rule(ins, name, profile, out)
    return out


def _axes(profile: ModuleProfile) -> str:
    return "motor 0 only" if profile.axes == 1 else f"motors 0..{profile.axes - 1}"


def _motor(ins: Instruction, name: str, profile: ModuleProfile, out: list[Finding]) -> None:
    on_motor = ins.command in _AXIS_MOTOR or (ins.command == 27 and ins.type in _WAIT_ON_MOTOR)
    if ins.command in (30, 31) and ins.motor == ALL:
        return
    if on_motor and ins.motor >= profile.axes:
        out.append(Finding("motor", f"{name}: motor {ins.motor} does not exist on {profile.name} "
                                    f"({_axes(profile)})"))


def _access(p_access: str, need: str) -> bool:
    return need in p_access or (need == "E" and "A" in p_access)


def _axis_param(ins: Instruction, name: str, profile: ModuleProfile, out: list[Finding]) -> None:
    need = _AXIS_PARAM.get(ins.command)
    if need is None:
        return
    p = profile.axis_parameters.get(ins.type)
    if p is None:
        out.append(Finding("type", f"{name}: {profile.name} has no axis parameter {ins.type}"))
    elif not _access(p.access, need):
        out.append(Finding("type", f"{name}: axis parameter {ins.type} ({p.name}) of {profile.name} "
                                   f"cannot be {_ACCESS_WORD[need]}"))


def _global_param(ins: Instruction, name: str, profile: ModuleProfile, out: list[Finding]) -> None:
    need = _GLOBAL_PARAM.get(ins.command)
    if need is None:
        return
    bank, number = ins.motor, ins.type
    if bank == USER_BANK:
        size = profile.storable_user_variables if need == "E" else profile.user_variables
        if number >= size:
            what = "storable user variables" if need == "E" else "user variables"
            out.append(Finding("type", f"{name}: {profile.name} has {size} {what} (0..{size - 1}), "
                                       f"not {number}"))
        return
    if bank not in profile.global_banks:  # bank 2 returned above
        banks = sorted(profile.global_banks)
        out.append(Finding("motor", f"{name}: {profile.name} has no global parameter bank {bank} "
                                    f"(banks {', '.join(map(str, banks))})"))
        return
    p = profile.global_parameters.get((bank, number))
    if p is None:
        out.append(Finding("type", f"{name}: {profile.name} has no global parameter {number} in bank {bank}"))
    elif not _access(p.access, need):
        out.append(Finding("type", f"{name}: global parameter {number} ({p.name}) of {profile.name} "
                                   f"cannot be {_ACCESS_WORD[need]}"))


def _io(ins: Instruction, name: str, profile: ModuleProfile, out: list[Finding]) -> None:
    if ins.command not in (14, 15):
        return
    port, bank = ins.type, ins.motor
    if not any(b == bank for b, _ in profile.io):
        out.append(Finding("motor", f"{name}: {profile.name} has no I/O bank {bank}"))
        return
    pullups = profile.extra.get("pullups")
    if port == ALL or (pullups and (bank, port) == (pullups["bank"], pullups["port"])):
        return
    p = profile.io.get((bank, port))
    if p is None:
        out.append(Finding("type", f"{name}: {profile.name} has no port {port} in I/O bank {bank}"))
    elif ins.command == 14 and "W" not in p.access:
        out.append(Finding("type", f"{name}: port {port} in bank {bank} ({p.name}) of {profile.name} "
                                   "is an input"))


def _coordinate(ins: Instruction, name: str, profile: ModuleProfile, out: list[Finding]) -> None:
    if ins.command in _COORDINATE and ins.type > profile.coordinates:
        out.append(Finding("type", f"{name}: {profile.name} has coordinates 0..{profile.coordinates}, "
                                   f"not {ins.type}"))
    if ins.command == 4 and ins.type == opcodes.MvpType.COORD and not 0 <= ins.value <= profile.coordinates:
        out.append(Finding("value", f"{name}: {profile.name} has coordinates 0..{profile.coordinates}, "
                                    f"not {ins.value}"))


def _interrupt(ins: Instruction, name: str, profile: ModuleProfile, out: list[Finding]) -> None:
    if ins.command not in (25, 26, 37):
        return
    if ins.type == ALL:  # EI/DI 255: all interrupts; VECT 255 names no vector (TMCM-6212 3.6.30-3.6.32)
        if ins.command == 37:
            out.append(Finding("type", f"{name}: 255 is not an interrupt vector (it switches all interrupts)"))
        return
    if ins.type not in profile.interrupts:
        out.append(Finding("type", f"{name}: {profile.name} has no interrupt {ins.type}"))


_Rule = Callable[[Instruction, str, "ModuleProfile", list[Finding]], None]
_RULES: tuple[_Rule, ...] = (_motor, _axis_param, _global_param, _io, _coordinate, _interrupt)
