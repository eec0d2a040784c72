"""Disassembler: program records back to TMCL source that re-assembles to identical bytes.

- Symbolic type names (ABS, TICKS, ADD, GE, ETO, ...) where the command has them;
- labels for the targets of JA, JC, CSUB, VECT, RST, DJNZ and CALL inside the program (given names,
  or ``L<address>``);
- with a module: ``#include <module>.inc`` and the bundled names for axis parameters (``AP...``),
  global parameters (``GP...``), interrupt vectors (``TI_...``) and motors (``Motor<n>``);
- a record that has no mnemonic form (a control command, an unknown opcode, a non-zero field that
  the command's operand forms cannot carry) becomes ``RAW command, type, motor, value``;
- the assembler appends a STOP, so one trailing ``STOP`` record is left out of the text; when the
  program does not end with a plain STOP the text starts with ``#nostop``.
"""
from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache

from ..protocol import opcodes
from ..protocol.opcodes import MOTOR, TYPE, VALUE
from .assembler import RAW, STOP, AsmError, assemble, include_key
from .binfile import BinFileError, Instruction, decode

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_RESERVED = {RAW}



@dataclass
class _Names:
    """Module names for operands (empty without a module)."""

    include: str = ""
    axis: dict[int, str] = field(default_factory=dict)
    globals: dict[tuple[int, int], str] = field(default_factory=dict)
    interrupts: dict[int, str] = field(default_factory=dict)
    motors: dict[int, str] = field(default_factory=dict)
    constants: set[str] = field(default_factory=set)


@cache
def _module_names(module: str) -> _Names:
    from ..modules.profile import load_profile
    from .gen_includes import camel
    prof = load_profile(module)
    key = include_key(prof.name)
    consts = assemble(f"#include {key}.inc", module=prof.name).constants

    def checked(name: str, number: int) -> str | None:
        return name if consts.get(name) == number else None

    names = _Names(include=f"{key}.inc", constants=set(consts))
    for p in prof.axis_parameters.values():
        if n := checked(f"AP{camel(p.name)}", p.number):
            names.axis[p.number] = n
    for g in prof.global_parameters.values():
        base = f"GP{camel(g.name)}"
        if n := checked(base, g.number) or checked(f"{base}_B{g.bank}", g.number):
            names.globals[(g.bank or 0, g.number)] = n
    for i in prof.interrupts.values():
        if n := checked(i.name, i.number):
            names.interrupts[i.number] = n
    if consts.get("TI_GLOBAL") == 255:
        names.interrupts.setdefault(255, "TI_GLOBAL")
    for a in range(prof.axes):
        if n := checked(f"Motor{a}", a):
            names.motors[a] = n
    return names


def _type_name(cmd: opcodes.Command, ins: Instruction, names: _Names) -> str | None:
    """The type operand as a symbol: the command's own names, then the module's parameter names."""
    text = opcodes.symbol_name(cmd, ins.type)
    if text is None and _names(cmd, opcodes.AXIS_PARAMETER, TYPE, ins.type):
        text = names.axis.get(ins.type)
    elif text is None and _names(cmd, opcodes.GLOBAL_PARAMETER, TYPE, ins.type):
        text = names.globals.get((ins.motor, ins.type))
    elif text is None and _names(cmd, opcodes.INTERRUPT, TYPE, ins.type):
        text = names.interrupts.get(ins.type)
    return text


def _names(cmd: opcodes.Command, what: str, fld: str, type: int) -> bool:
    """Does field `fld` of `cmd` name a `what` (opcodes.Meaning) with this type field?"""
    meaning = cmd.naming(what, type)
    return meaning is not None and meaning.field == fld


def _operand_text(cmd: opcodes.Command, fld: str, ins: Instruction, labels: Mapping[int, str],
                  names: _Names) -> str:
    num = {TYPE: ins.type, MOTOR: ins.motor, VALUE: ins.value}[fld]
    text = None
    if fld == TYPE:
        text = _type_name(cmd, ins, names)
    elif fld == MOTOR and cmd.number in opcodes.AXIS_COMMANDS:  # an axis whatever the type
        text = names.motors.get(num)
    elif fld == VALUE and cmd.label:
        text = labels.get(num)
    return text if text is not None else str(num)


def _text(ins: Instruction, labels: Mapping[int, str], names: _Names) -> str:
    cmd = opcodes.COMMANDS.get(ins.command)
    form = opcodes.choose_form(cmd, ins.type, ins.motor, ins.value) if cmd and cmd.mnemonic else None
    if cmd is None or form is None:
        return f"{RAW} {ins.command}, {ins.type}, {ins.motor}, {ins.value}"
    parts = [_operand_text(cmd, fld, ins, labels, names) for fld in form]
    return f"{cmd.mnemonic} {', '.join(parts)}".rstrip()


ProgramData = bytes | bytearray | memoryview | Iterable[Sequence[int]]
"""A binary image, or instructions as (command, type, motor, value) sequences."""


def _instructions(program: ProgramData) -> list[Instruction]:
    """The instructions of a binary image or of a sequence of (command, type, motor, value)."""
    if isinstance(program, (bytes, bytearray, memoryview)):
        return decode(program)
    if isinstance(program, str):
        raise TypeError("disassemble() takes the bytes of a binary file or a list of instructions, not str")
    out = []
    for index, ins in enumerate(program):
        fields = tuple(ins) if isinstance(ins, (tuple, list)) else ()
        if len(fields) != 4 or not all(isinstance(f, int) for f in fields):
            raise BinFileError(f"instruction {index}: expected (command, type, motor, value) integers, "
                               f"got {ins!r}")
        out.append(Instruction(*fields))
        out[-1].encode()  # BinFileError for a field out of range
    return out


def _given_labels(labels: Mapping[str, int] | None, names: _Names) -> dict[int, str]:
    """Address -> the caller's label name (the first by name), for names the assembler accepts."""
    given: dict[int, str] = {}
    for name, addr in sorted((labels or {}).items(), key=lambda kv: kv[0]):
        if _IDENT.fullmatch(name) and name.upper() not in _RESERVED and name not in names.constants:
            given.setdefault(addr, name)
    return given


def _jump_targets(body: list[Instruction], given: dict[int, str], names: _Names) -> dict[int, str]:
    """Address -> label for every jump target inside the program and every given label there;
    ``L<address>`` (with ``_`` appended until unique) where no name was given."""
    targets: dict[int, str] = {}
    taken = set(given.values()) | names.constants
    for ins in body:
        cmd = opcodes.COMMANDS.get(ins.command)
        if cmd is None or not cmd.label or opcodes.format_instruction(*ins) is None:
            continue
        if 0 <= ins.value <= len(body) and ins.value not in targets:
            name = given.get(ins.value, f"L{ins.value}")
            while ins.value not in given and name in taken:
                name += "_"
            targets[ins.value] = name
            taken.add(name)
    for addr, name in given.items():  # keep every given label that lies inside the program
        if 0 <= addr <= len(body):
            targets.setdefault(addr, name)
    return targets


def _source_lines(body: list[Instruction], targets: Mapping[int, str], names: _Names,
                  comments: bool) -> list[str]:
    """One line per instruction, indented, with label lines before their addresses."""
    lines = []
    texts = [_text(i, targets, names) for i in body]
    width = max((len(t) for t in texts), default=0)
    for addr, text in enumerate(texts):
        if addr in targets:
            lines.append(f"{targets[addr]}:")
        lines.append(f"    {text:<{width}}  // {addr}" if comments else f"    {text}")
    if len(body) in targets:
        lines.append(f"{targets[len(body)]}:")
    return lines


def disassemble(program: ProgramData, *, labels: Mapping[str, int] | None = None,
                comments: bool = True, module: str | None = None) -> str:
    """TMCL source for a binary image (8-byte records) or a list of instructions.

    `labels` (name -> address, e.g. from Program.labels) names the jump targets; other targets
    get ``L<address>``. With `comments`, each line ends with ``// <address>``. With `module`, the
    text includes that module's bundled names (the output then needs the bundled include files).
    """
    instrs = _instructions(program)
    tail_stop = bool(instrs) and instrs[-1] == STOP
    body = instrs[:-1] if tail_stop else instrs
    try:
        names = _module_names(module) if module else _Names()
    except (KeyError, AsmError) as exc:
        raise ValueError(f"cannot use the names of module {module!r}: {exc}") from None
    targets = _jump_targets(body, _given_labels(labels, names), names)
    lines = [] if tail_stop else ["#nostop"]
    if names.include:
        lines.append(f"#include {names.include}")
    lines += _source_lines(body, targets, names, comments)
    return "\n".join(lines) + "\n"
