"""From statements to the program: each operand's value in its field (type, motor/bank 0..255,
value signed 32 bit), the instructions, the module's checks (lang/capabilities_check.py: warnings,
errors with `strict`; the program memory size: an error; without a module only the commands of
direct mode only) and the appended STOP."""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..protocol import opcodes
from ..protocol.frame import to_int32
from ..protocol.opcodes import MOTOR, TYPE, VALUE
from .binfile import Instruction
from .capabilities_check import check as check_instruction
from .capabilities_check import direct_only
from .diagnostics import ERROR, WARNING, Diagnostic
from .errors import AsmError, fail
from .output import STOP, Program, SourceLine
from .state import Operand, State, Stmt
from .symbols import lookup, value_of

if TYPE_CHECKING:
    from ..modules.profile import ModuleProfile

_RAW_FIELDS = ("command", TYPE, MOTOR, VALUE)
_FIELD_WORD = {"type": "type", "motor": "motor/bank", "command": "command"}


def _operand_value(stmt: Stmt, op: Operand, fld: str, st: State) -> int:
    cmd = stmt.command
    if cmd is not None and fld == TYPE and cmd.symbols and op.expr.kind == "name":
        sym = opcodes.lookup_symbol(cmd, op.expr.name)
        if sym is not None:
            return sym
        if op.expr.name not in (*st.labels, *st.constants, *st.poisoned):
            table = "|".join(cmd.symbol_table())
            fail(stmt.where, op.column, f"unknown {cmd.mnemonic} type {op.expr.name!r}; expected {table}")
    v = value_of(op.expr, stmt.where, st)
    if fld in (TYPE, MOTOR, "command"):
        if not 0 <= v <= 255:
            fail(stmt.where, op.column, f"{_FIELD_WORD[fld]} operand must be 0..255, got {v}")
    elif not -(1 << 31) <= v <= 0xFFFFFFFF:
        fail(stmt.where, op.column, f"value operand out of 32-bit range: {v}")
    return to_int32(v) if fld == VALUE else v


def _encode_stmt(stmt: Stmt, st: State) -> Instruction:
    if stmt.command is None:  # RAW
        if len(stmt.operands) != 4:
            col = stmt.operands[-1].column if stmt.operands else stmt.column
            fail(stmt.where, col, "expected RAW <command>, <type>, <motor>, <value>")
        c, t, m, v = (_operand_value(stmt, op, f, st) for op, f in
                      zip(stmt.operands, _RAW_FIELDS, strict=True))
        return Instruction(c, t, m, v)
    cmd = stmt.command
    form = cmd.form_for(len(stmt.operands))
    if form is None:
        col = stmt.operands[-1].column if stmt.operands else stmt.column
        n = len(stmt.operands)
        fail(stmt.where, col, f"{cmd.mnemonic} does not take {n} operand{'s' if n != 1 else ''}; "
             f"expected {cmd.usage()}")
    fields = {TYPE: 0, MOTOR: 0, VALUE: 0}
    for op, fld in zip(stmt.operands, form, strict=True):
        fields[fld] = _operand_value(stmt, op, fld, st)
    return Instruction(cmd.number, fields[TYPE], fields[MOTOR], fields[VALUE])


def _field_column(stmt: Stmt, fld: str) -> int:
    """Column of the operand that gave field `fld` (the mnemonic's when none did)."""
    names = _RAW_FIELDS if stmt.command is None else stmt.command.form_for(len(stmt.operands)) or ()
    for op, name in zip(stmt.operands, names, strict=False):
        if name == fld:
            return op.column
    return stmt.column


def _check_module(stmt: Stmt, ins: Instruction, st: State, profile: ModuleProfile | None) -> None:
    """The module's checks; without a module, only what no module can do (a command of direct mode
    only in a program, capabilities_check.direct_only)."""
    if profile is None:
        only = direct_only(ins)
        findings = [] if only is None else [only]
    else:
        findings = check_instruction(ins, profile)
    for finding in findings:
        col = _field_column(stmt, finding.field)
        severity = ERROR if st.strict else WARNING
        diag = Diagnostic(stmt.where.file, stmt.where.line, col, finding.message, severity, (stmt.where.seq, col))
        (st.errors if st.strict else st.warnings).add(diag)


def _encode_all(st: State, profile: ModuleProfile | None) -> tuple[list[Instruction], list[SourceLine | None]]:
    instructions: list[Instruction] = []
    sources: list[SourceLine | None] = []
    for stmt in st.statements:
        try:
            ins = _encode_stmt(stmt, st)
        except AsmError as exc:
            st.report(exc)
            continue
        _check_module(stmt, ins, st, profile)
        instructions.append(ins)
        sources.append(SourceLine(stmt.where.file, stmt.where.line, stmt.where.text))
    if st.append_stop:
        instructions.append(STOP)
        sources.append(None)
    return instructions, sources


def _check_size(st: State, profile: ModuleProfile | None) -> None:
    """The program must fit the module's memory: the error points at the first instruction that
    does not fit (at none when the source has no instruction)."""
    size = len(st.statements) + int(st.append_stop)
    if profile is None or st.origin + size <= profile.program_memory:
        return
    at = f" from address {st.origin}" if st.origin else ""
    message = f"program has {size} instructions{at}; {profile.name} program memory holds {profile.program_memory}"
    if not st.statements:
        raise AsmError(st.filename, 0, 0, message)
    over = st.statements[max(0, min(profile.program_memory - st.origin, len(st.statements) - 1))]
    fail(over.where, over.column, message)


def finish(st: State, profile: ModuleProfile | None) -> Program:
    """The program of the statements read into `st`; AsmError with every error found."""
    instructions, sources = _encode_all(st, profile)
    try:
        _check_size(st, profile)
    except AsmError as exc:
        st.report(exc)
    constants = {}
    for name in st.constants:
        try:
            constants[name] = lookup(name, 1, st.constants[name][0].where, st)
        except AsmError as exc:
            st.report(exc)
    if len(st.errors):
        raise AsmError.from_collected(st.errors, st.warnings)
    labels = {name: addr for name, (addr, _) in st.labels.items()}
    return Program(instructions, labels, constants, sources, profile.name if profile else None,
                   st.filename, st.origin, st.warnings.items, st.warnings.more)
