"""One direct-mode instruction from text, as `opentmcl send` and the dashboard console read it.

An instruction is written as in TMCL source (TMCM-6212 manual 3.6: ``MVP ABS, 0, 1000``,
``GAP 1, 0``, ``SAP 4, 0, 51200``) or, for control commands that have no mnemonic (manual
3.6.36), as up to four numbers ``COMMAND, TYPE, MOTOR, VALUE`` (e.g. ``136, 0, 0, 0``).
"""
from __future__ import annotations

from ..limits import LiteralTooLong, shown
from ..protocol.opcodes import parse_number
from .assembler import AsmError, assemble


class InstructionError(ValueError):
    """Text that is not one direct-mode instruction (the message names the text)."""


def parse_direct(text: str) -> tuple[int, int, int, int]:
    """(command, type, motor, value) of one instruction; InstructionError if it cannot be read.

    Mnemonic forms go through the assembler (symbolic names, expressions such as ``51200*2``);
    control commands are written as up to four numbers.
    """
    parts = [p.strip() for p in text.replace(",", " ").split()]
    try:
        numeric = bool(parts) and parse_number(parts[0]) is not None
        nums = [parse_number(p) for p in parts] if numeric else []
    except LiteralTooLong as exc:
        raise InstructionError(str(exc)) from None
    if not numeric:
        return _parse_mnemonic(text)
    fields = [n for n in nums if n is not None]
    if len(nums) > 4 or len(fields) != len(nums):
        raise InstructionError(f"{shown(text)}: expected COMMAND, TYPE, MOTOR, VALUE as numbers")
    command, type_, motor, value = (fields + [0, 0, 0])[:4]
    return command, type_, motor, value


def _parse_mnemonic(text: str) -> tuple[int, int, int, int]:
    if "\n" in text:
        raise InstructionError(f"{shown(text)}: one instruction per argument")
    try:
        program = assemble(text, filename="<send>", append_stop=False)
    except AsmError as exc:
        raise InstructionError(f"{shown(text)}: {exc.message}") from None
    if len(program.instructions) != 1:
        raise InstructionError(f"{shown(text)}: expected one instruction")
    ins = program.instructions[0]
    return ins.command, ins.type, ins.motor, ins.value
