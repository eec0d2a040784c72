"""Assembler for TMCL-IDE source (TMCM-6212 manual 2.4, 3.3, 3.5.6.4, chapter 7).

Source syntax, one statement per line:

- ``// comment`` to the end of the line;
- ``Label:`` defines a label (the address of the next instruction); it may share the line with an
  instruction (``Loop: MVP ABS, 0, 1000``) and may have spaces before the colon (``Loop :``);
- ``Name = expression`` defines a constant (7.3 "Using Symbolic Constants");
- ``#include file`` reads another source file (searched in the including file's directory, the
  include path, then the bundled include files of the selected module); a file is read once;
- ``#nostop`` suppresses the STOP that is otherwise appended after the last instruction;
- ``MNEMONIC operand, operand, ...`` - mnemonics are case-insensitive; operands are expressions of
  decimal, ``0x``/``$`` hex and ``0b`` binary literals, constants and labels with ``+ - * / % & | ^
  ~ << >>`` and parentheses, or the command's symbolic names (ABS, TICKS, ADD, GE, ETO, ...);
- ``RAW command, type, motor, value`` emits any instruction verbatim (used by the disassembler for
  records that have no mnemonic form).

Output: the program (a list of instructions), its 8-byte-record image, the label table, a
listing and the warnings (`Program.warnings`). Every error is found in one run: AsmError carries
them all, in source order (lang/diagnostics.py), each naming file, line and column. With a module,
instructions it cannot execute (lang/capabilities_check.py) are warnings, or errors with `strict`.
"""
from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

from ..limits import TEXT_MAX, InputTooLarge, LiteralTooLong, read_text
from ..protocol import opcodes
from ..protocol.frame import to_int32
from ..protocol.opcodes import MOTOR, TYPE, VALUE, Command
from .binfile import Instruction, encode
from .capabilities_check import check as check_instruction
from .diagnostics import ERROR, WARNING, Collector, Diagnostic, merged, more_line

if TYPE_CHECKING:
    from ..modules.profile import ModuleProfile

STOP = Instruction(28, 0, 0, 0)
RAW = "RAW"
INCLUDE_DIR = Path(__file__).resolve().parent / "include"
DEFAULT_MODULE = "TMCM-6212"
MAX_INCLUDE_DEPTH = 32
MAX_EXPR_DEPTH = 100
MAX_EXPR_TOKENS = 1000      # numbers, names and operators in one expression
MAX_CONSTANT_DEPTH = 100    # constants defined through constants, this many levels deep
MAX_INTERMEDIATE = 1 << 64  # expression results beyond this are errors (keeps numbers small)

_IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
_LABEL_RE = re.compile(rf"\s*({_IDENT})\s*:")
_CONST_RE = re.compile(rf"\s*({_IDENT})\s*=(.*)\Z", re.S)
_WORD_RE = re.compile(rf"\s*({_IDENT})")
_BLANK_RE = re.compile(r"\s*\Z")
_TOKEN_RE = re.compile(
    r"\s*(?:(?P<num>0[xX][0-9A-Fa-f]+|\$[0-9A-Fa-f]+|0[bB][01]+|[0-9]+)"
    rf"|(?P<name>{_IDENT})|(?P<op><<|>>|[-+*/%&|^~()]))"
)


class AsmError(Exception):
    """Errors in TMCL source. `file`, `line`, `column` (1-based; line 0: no position) and `message`
    are those of the first error; `errors` lists every error in source order (at most
    diagnostics.MAX_REPORTED, `more` counts the rest), `warnings` and `warnings_more` likewise.
    str() is one line per error."""

    def __init__(self, file: str, line: int, column: int, message: str, *,
                 order: tuple[int, int] = (0, 0)):
        self.file, self.line, self.column, self.message = file, line, column, message
        self.errors = [Diagnostic(file, line, column, message, ERROR, order)]
        self.warnings: list[Diagnostic] = []
        self.more = self.warnings_more = 0
        super().__init__(str(self.errors[0]))

    @classmethod
    def from_collected(cls, errors: Collector, warnings: Collector) -> AsmError:
        first, *_ = kept = errors.items
        exc = cls(first.file, first.line, first.column, first.message, order=first.order)
        exc.errors, exc.more = kept, errors.more
        exc.warnings, exc.warnings_more = warnings.items, warnings.more
        exc.args = ("\n".join(str(d) for d in kept) + (f"\n{more_line(exc.more, 'error')}" if exc.more else ""),)
        return exc

    @property
    def diagnostic(self) -> Diagnostic:
        return self.errors[0]

    def diagnostics(self) -> list[Diagnostic]:
        """Errors and warnings together, in source order."""
        return merged(self.errors, self.warnings)


class _Cascade(AsmError):
    """A consequence of an error already reported (a constant whose definition failed)."""


@dataclass(frozen=True)
class SourceLine:
    file: str
    line: int
    text: str


@dataclass
class Program:
    """Result of assembly."""

    instructions: list[Instruction]
    labels: dict[str, int]
    constants: dict[str, int]
    source: list[SourceLine | None]  # per instruction; None for the appended STOP
    module: str | None = None
    filename: str = "<source>"
    origin: int = 0  # program memory address of the first instruction (labels are absolute)
    warnings: list[Diagnostic] = field(default_factory=list)
    """What the module cannot execute (only with a module), in source order."""
    warnings_more: int = 0
    """Warnings beyond diagnostics.MAX_REPORTED, counted but not listed."""

    def image(self) -> bytes:
        """The binary file contents (TMCL-IDE format: 8-byte records, no header)."""
        return encode(self.instructions)

    def symbol_file(self) -> str:
        """Labels and their addresses, one per line: ``Name<TAB>address``, by address."""
        rows = sorted(self.labels.items(), key=lambda kv: (kv[1], kv[0]))
        return "".join(f"{name}\t{addr}\n" for name, addr in rows)

    def listing(self) -> str:
        """Address, record bytes and source of every instruction, with labels on their own lines."""
        by_addr: dict[int, list[str]] = {}
        for name, addr in self.labels.items():
            by_addr.setdefault(addr, []).append(name)
        out = []
        for index, ins in enumerate(self.instructions):
            addr = self.origin + index
            for name in sorted(by_addr.get(addr, ())):
                out.append(f"{'':4}  {'':23}  {'':>6}  {name}:")
            raw = " ".join(f"{b:02X}" for b in ins.encode())
            src = self.source[index]
            if src is None:
                out.append(f"{addr:04d}  {raw}  {'':>6}  STOP  // appended")
                continue
            where = str(src.line) if src.file == self.filename else f"{src.file}:{src.line}"
            out.append(f"{addr:04d}  {raw}  {where:>6}  {src.text.strip()}")
        for name in sorted(by_addr.get(self.origin + len(self.instructions), ())):
            out.append(f"{'':4}  {'':23}  {'':>6}  {name}:")
        return "\n".join(out) + "\n"


# --- expressions -----------------------------------------------------------------------------

@dataclass(frozen=True)
class _Expr:
    kind: str  # num | name | un | bin
    column: int
    value: int = 0
    name: str = ""
    op: str = ""
    args: tuple[_Expr, ...] = ()


_BINARY_LEVELS = (("|",), ("^",), ("&",), ("<<", ">>"), ("+", "-"), ("*", "/", "%"))

_Fail = Callable[[int, str], NoReturn]
"""Raises AsmError at a column of the line being read."""


class _ExprParser:
    def __init__(self, text: str, col0: int, err: _Fail):
        self.tokens: list[tuple[str, str, int]] = []
        self.err = err
        pos = 0
        while pos < len(text):
            if _BLANK_RE.match(text, pos):
                break
            if len(self.tokens) == MAX_EXPR_TOKENS:
                err(self.tokens[-1][2], f"expression longer than {MAX_EXPR_TOKENS} numbers, names and operators")
            m = _TOKEN_RE.match(text, pos)
            if not m:
                bad = len(text) - len(text[pos:].lstrip())
                err(col0 + bad, f"unexpected character {text[bad]!r} in expression")
            kind = m.lastgroup
            assert kind is not None, "every alternative of _TOKEN_RE is a named group"
            self.tokens.append((kind, m.group(kind), col0 + m.start(kind)))
            pos = m.end()
        self.i = 0
        self.depth = 0
        self.end_col = col0 + len(text.rstrip())

    def parse(self) -> _Expr:
        if not self.tokens:
            self.err(self.end_col, "missing operand")
        e = self._binary(0)
        if self.i < len(self.tokens):
            _, tok, col = self.tokens[self.i]
            self.err(col, f"unexpected {tok!r} in expression")
        return e

    def _peek(self) -> tuple[str, str, int] | None:
        return self.tokens[self.i] if self.i < len(self.tokens) else None

    def _binary(self, level: int) -> _Expr:
        if level == len(_BINARY_LEVELS):
            return self._unary()
        left = self._binary(level + 1)
        while (t := self._peek()) and t[0] == "op" and t[1] in _BINARY_LEVELS[level]:
            self.i += 1
            right = self._binary(level + 1)
            left = _Expr("bin", t[2], op=t[1], args=(left, right))
        return left

    def _unary(self) -> _Expr:
        t = self._peek()
        if t is None:
            self.err(self.end_col, "expression ends too early")
        kind, tok, col = t
        self.i += 1
        self.depth += 1
        if self.depth > MAX_EXPR_DEPTH:
            self.err(col, f"expression nested deeper than {MAX_EXPR_DEPTH} levels")
        try:
            return self._primary(kind, tok, col)
        finally:
            self.depth -= 1

    def _primary(self, kind: str, tok: str, col: int) -> _Expr:
        if kind == "op" and tok in "+-~":
            return _Expr("un", col, op=tok, args=(self._unary(),))
        if kind == "op" and tok == "(":
            e = self._binary(0)
            close = self._peek()
            if not close or close[1] != ")":
                self.err(close[2] if close else self.end_col, "missing ')'")
            self.i += 1
            return e
        if kind == "num":
            try:
                value = opcodes.parse_number(tok)
            except LiteralTooLong as exc:
                self.err(col, str(exc))
            assert value is not None, "the num group of _TOKEN_RE only matches literals"
            return _Expr("num", col, value=value)
        if kind == "name":
            return _Expr("name", col, name=tok)
        self.err(col, f"unexpected {tok!r} in expression")


def _apply(op: str, a: int, b: int | None = None) -> int:
    if b is None:
        return a if op == "+" else -a if op == "-" else ~a
    if op in "/%" and b == 0:
        raise ZeroDivisionError
    if op == "/":
        q = abs(a) // abs(b)
        return q if (a >= 0) == (b >= 0) else -q  # C-style truncation
    if op == "%":
        return a - b * _apply("/", a, b)
    if op in ("<<", ">>"):
        if not 0 <= b <= 63:
            raise ValueError(f"shift count {b} out of range 0..63")
        return a << b if op == "<<" else a >> b
    ops = {"+": int.__add__, "-": int.__sub__, "*": int.__mul__, "&": int.__and__, "|": int.__or__,
           "^": int.__xor__}
    return ops[op](a, b)


# --- statements ------------------------------------------------------------------------------

@dataclass
class _Where:
    file: str
    line: int
    text: str
    seq: int = 0  # position in reading order (an include's lines come where it is included)


@dataclass
class _Operand:
    text: str
    column: int
    expr: _Expr


@dataclass
class _Stmt:
    where: _Where
    command: Command | None  # None for RAW
    mnemonic: str
    column: int
    operands: list[_Operand]


@dataclass
class _Const:
    where: _Where
    column: int
    expr: _Expr


@dataclass
class _State:
    module: str | None
    include_path: list[Path]
    append_stop: bool = True
    filename: str = "<source>"
    origin: int = 0
    statements: list[_Stmt] = field(default_factory=list)
    labels: dict[str, tuple[int, _Where]] = field(default_factory=dict)
    constants: dict[str, list[_Const]] = field(default_factory=dict)
    included: set[str] = field(default_factory=set)
    values: dict[str, int] = field(default_factory=dict)
    resolving: list[str] = field(default_factory=list)
    poisoned: set[str] = field(default_factory=set)  # constants whose definition failed
    errors: Collector = field(default_factory=Collector)
    warnings: Collector = field(default_factory=Collector)
    lines_read: int = 0
    strict: bool = False

    def report(self, exc: AsmError) -> None:
        if not isinstance(exc, _Cascade):
            self.errors.add(exc.diagnostic)


def _fail(where: _Where, column: int, message: str) -> NoReturn:
    raise AsmError(where.file, where.line, column, message, order=(where.seq, column))


def bundled_include(name: str, module: str | None = None) -> Path | None:
    """Path of a bundled include file: the module's own variant (``<key>_<name>``) first."""
    try:
        key = include_key(module)
    except KeyError:
        key = None
    for candidate in ([f"{key}_{name}"] if key else []) + [name]:
        path = INCLUDE_DIR / candidate
        if _is_file(path):
            return path
    return None


def _is_file(path: Path) -> bool:
    try:
        return path.is_file()
    except (OSError, ValueError):  # e.g. a NUL byte or an over-long name
        return False


def include_key(module: str | None) -> str:
    """File-name key of a module's bundled includes: TMCM-6212 -> tmcm6212, PD86-1180 -> pd86_1180."""
    from ..modules.profile import load_profile
    name = load_profile(module or DEFAULT_MODULE).name
    head, _, tail = name.lower().partition("-")
    return f"{head}{tail}" if head == "tmcm" else f"{head}_{tail}"


def _find_include(name: str, current: Path | None, st: _State) -> Path | None:
    dirs = ([current.parent] if current else []) + st.include_path
    for d in dirs:
        p = d / name
        if _is_file(p):
            return p
    return bundled_include(name, st.module)


def _strip_comment(text: str) -> str:
    cut = text.find("//")
    return text if cut < 0 else text[:cut]


def _split_operands(text: str, col0: int) -> list[tuple[str, int]]:
    """Comma-separated operand texts with the 1-based column where each starts."""
    out, start = [], 0
    for i, ch in enumerate(text + ","):
        if ch == ",":
            piece = text[start:i]
            lead = len(piece) - len(piece.lstrip())
            out.append((piece.strip(), col0 + start + lead))
            start = i + 1
    return out


def _read_file(path: Path, display: str, st: _State, where: _Where | None, depth: int) -> None:
    key = str(path.resolve())
    if key in st.included:
        return
    st.included.add(key)
    try:
        text = read_text(path, TEXT_MAX, "program source", errors="replace")
    except (OSError, InputTooLarge) as exc:
        why = str(exc) if isinstance(exc, InputTooLarge) else exc.strerror or str(exc)
        if where:
            _fail(where, 1, f"cannot read include file {display}: {why}")
        raise AsmError(display, 0, 0, f"cannot read file: {why}") from None
    _read_text(text, display, path, st, depth)


def _read_text(text: str, display: str, path: Path | None, st: _State, depth: int) -> None:
    text = text.removeprefix("\ufeff")
    for lineno, raw in enumerate(text.splitlines(), 1):
        st.lines_read += 1
        where = _Where(display, lineno, raw, st.lines_read)
        try:
            _read_line(raw, where, path, st, depth)
        except AsmError as exc:
            st.report(exc)


def _read_line(raw: str, where: _Where, path: Path | None, st: _State, depth: int) -> None:
    stripped = raw.lstrip()
    if stripped.startswith("#"):
        _directive(raw, where, path, st, depth)
        return
    line = _strip_comment(raw)
    pos = 0
    while m := _LABEL_RE.match(line, pos):
        name = m.group(1)
        _define_label(name, m.start(1) + 1, where, st)
        pos = m.end()
    rest = line[pos:]
    if not rest.strip():
        return
    if m := _CONST_RE.match(rest):
        name = m.group(1)
        col = pos + m.start(1) + 1
        expr_col = pos + m.start(2) + 1
        try:
            expr = _ExprParser(m.group(2), expr_col, lambda c, msg: _fail(where, c, msg)).parse()
        except AsmError:
            st.poisoned.add(name)  # its uses are not errors of their own
            raise
        _define_constant(name, col, expr, where, st)
        return
    m = _WORD_RE.match(rest)
    if not m:
        col = pos + len(rest) - len(rest.lstrip()) + 1
        _fail(where, col, "expected a label, a constant definition or an instruction")
    mnemonic = m.group(1)
    col = pos + m.start(1) + 1
    after = rest[m.end():]
    if after and not after[0].isspace():
        _fail(where, col + len(mnemonic), f"expected a space after {mnemonic!r}")
    command = None
    if mnemonic.upper() != RAW:
        try:
            command = opcodes.by_mnemonic(mnemonic)
        except opcodes.UnknownCommand:
            _fail(where, col, f"unknown mnemonic {mnemonic!r}")
    ops_col = pos + m.end() + 1
    operands = []
    if after.strip():
        for text, ocol in _split_operands(after, ops_col):
            if not text:
                usage = command.usage() if command else "RAW <command>, <type>, <motor>, <value>"
                _fail(where, ocol, f"empty operand; expected {usage}")
            expr = _ExprParser(text, ocol, lambda c, msg: _fail(where, c, msg)).parse()
            operands.append(_Operand(text, ocol, expr))
    st.statements.append(_Stmt(where, command, mnemonic.upper(), col, operands))


def _directive(raw: str, where: _Where, path: Path | None, st: _State, depth: int) -> None:
    body = raw.lstrip()
    col = len(raw) - len(body) + 1
    m = re.match(r"#\s*(\w+)", body)
    word = m.group(1).lower() if m else ""
    if m is None or word not in ("include", "nostop"):
        _fail(where, col, f"unknown directive {body.split()[0]!r}; expected #include <file> or #nostop")
    if word == "include":
        arg = body[m.end():]
        arg_stripped = arg.strip()
        if arg_stripped.startswith(('"', "<")):
            close = '"' if arg_stripped[0] == '"' else ">"
            end = arg_stripped.find(close, 1)
            if end < 0:
                _fail(where, col, f"missing closing {close} in #include")
            name = arg_stripped[1:end]
        else:
            name = _strip_comment(arg).strip()
        if not name:
            _fail(where, col, "expected a file name: #include <file>")
        if depth >= MAX_INCLUDE_DEPTH:
            _fail(where, col, f"includes nested deeper than {MAX_INCLUDE_DEPTH}")
        found = _find_include(name, path, st)
        if found is None:
            _fail(where, col, f"include file {name!r} not found (searched the source directory, "
                  f"the include path and the bundled includes)")
        display = f"<bundled>/{found.name}" if found.parent == INCLUDE_DIR else str(found)
        _read_file(found, display, st, where, depth + 1)
    else:  # nostop
        if _strip_comment(body[m.end():]).strip():
            _fail(where, col, "#nostop takes no argument")
        st.append_stop = False


def _define_label(name: str, col: int, where: _Where, st: _State) -> None:
    if name in st.labels:
        first = st.labels[name][1]
        _fail(where, col, f"label {name!r} already defined at {first.file}:{first.line}")
    if name in st.constants:
        first = st.constants[name][0].where
        _fail(where, col, f"{name!r} is already a constant (defined at {first.file}:{first.line})")
    st.labels[name] = (st.origin + len(st.statements), where)


def _define_constant(name: str, col: int, expr: _Expr, where: _Where, st: _State) -> None:
    if name in st.labels:
        first = st.labels[name][1]
        _fail(where, col, f"{name!r} is already a label (defined at {first.file}:{first.line})")
    st.constants.setdefault(name, []).append(_Const(where, col, expr))


# --- evaluation ------------------------------------------------------------------------------

def _names_like(name: str, st: _State) -> list[str]:
    low = name.lower()
    return sorted(n for n in (*st.labels, *st.constants) if n.lower() == low and n != name)


def _lookup(name: str, col: int, where: _Where, st: _State) -> int:
    if name in st.labels:
        return st.labels[name][0]
    if name in st.values:
        return st.values[name]
    if name in st.poisoned:
        raise _Cascade(where.file, where.line, col, f"{name!r} has an error in its definition")
    if name in st.constants:
        return _resolve(name, col, where, st)
    hint = _names_like(name, st)
    extra = f" (names are case-sensitive; did you mean {hint[0]!r}?)" if hint else ""
    _fail(where, col, f"undefined symbol {name!r}{extra}")


def _resolve(name: str, col: int, where: _Where, st: _State) -> int:
    """The value of constant `name` (every definition must agree); an error poisons it."""
    try:
        return _resolve_checked(name, col, where, st)
    except AsmError:
        st.poisoned.add(name)
        raise


def _resolve_checked(name: str, col: int, where: _Where, st: _State) -> int:
    if name in st.resolving:
        chain = " -> ".join(st.resolving[st.resolving.index(name):] + [name])
        _fail(where, col, f"constant defined in terms of itself: {chain}")
    if len(st.resolving) > MAX_CONSTANT_DEPTH:
        _fail(where, col, f"constant {st.resolving[0]!r} is defined through more than "
                          f"{MAX_CONSTANT_DEPTH} levels of other constants (down to {name!r})")
    st.resolving.append(name)
    try:
        defs = st.constants[name]
        first = _eval(defs[0].expr, defs[0].where, st)
        for other in defs[1:]:
            v = _eval(other.expr, other.where, st)
            if v != first:
                _fail(other.where, other.column,
                      f"constant {name!r} redefined as {v} (was {first} at "
                      f"{defs[0].where.file}:{defs[0].where.line})")
    finally:
        st.resolving.pop()
    st.values[name] = first
    return first


def _eval(e: _Expr, where: _Where, st: _State) -> int:
    return _walk(e, lambda node: _lookup(node.name, node.column, where, st), lambda c, msg: _fail(where, c, msg))


def _walk(e: _Expr, name_value: Callable[[_Expr], int], fail: _Fail) -> int:
    """The value of `e`, without recursion (a long chain like 1+1+...+1 is a deep tree)."""
    todo: list[tuple[_Expr, bool]] = [(e, False)]
    values: list[int] = []
    while todo:
        node, ready = todo.pop()
        if node.kind == "num":
            values.append(node.value)
        elif node.kind == "name":
            values.append(name_value(node))
        elif not ready:
            todo.append((node, True))
            todo.extend((a, False) for a in reversed(node.args))
        else:
            n = len(node.args)
            vals = values[-n:]
            del values[-n:]
            values.append(_combine(node, vals, fail))
    return values[0]


def _combine(e: _Expr, vals: list[int], fail: _Fail) -> int:
    try:
        result = _apply(e.op, *vals)
        if abs(result) > MAX_INTERMEDIATE:
            fail(e.column, "expression value out of range (more than 64 bits)")
        return result
    except ZeroDivisionError:
        fail(e.column, "division by zero")
    except ValueError as exc:
        fail(e.column, str(exc))


class ExpressionError(ValueError):
    """An expression `evaluate` cannot read or compute; `column` (0-based) is where."""

    def __init__(self, column: int, message: str) -> None:
        super().__init__(message)
        self.column = column


def evaluate(text: str, lookup: Callable[[str], int]) -> int:
    """The value of `text`, written as an operand of this assembler (literals, names, ``+ - * / %
    & | ^ ~ << >>`` and parentheses, C-style division), each name's value given by `lookup` (which
    raises for a name it does not know). ExpressionError for text that is no expression."""

    def fail(column: int, message: str) -> NoReturn:
        raise ExpressionError(column, message)

    return _walk(_ExprParser(text, 0, fail).parse(), lambda node: lookup(node.name), fail)


def _operand_value(stmt: _Stmt, op: _Operand, fld: str, st: _State) -> int:
    cmd = stmt.command
    if cmd is not None and fld == TYPE and cmd.symbols and op.expr.kind == "name":
        sym = opcodes.lookup_symbol(cmd, op.expr.name)
        if sym is not None:
            return sym
        if op.expr.name not in (*st.labels, *st.constants, *st.poisoned):
            table = "|".join(cmd.symbol_table())
            _fail(stmt.where, op.column, f"unknown {cmd.mnemonic} type {op.expr.name!r}; expected {table}")
    v = _eval(op.expr, stmt.where, st)
    if fld in (TYPE, MOTOR, "command"):
        if not 0 <= v <= 255:
            what = {"type": "type", "motor": "motor/bank", "command": "command"}[fld]
            _fail(stmt.where, op.column, f"{what} operand must be 0..255, got {v}")
    elif not -(1 << 31) <= v <= 0xFFFFFFFF:
        _fail(stmt.where, op.column, f"value operand out of 32-bit range: {v}")
    return to_int32(v) if fld == VALUE else v


def _encode_stmt(stmt: _Stmt, st: _State, profile: ModuleProfile | None) -> Instruction:
    if stmt.command is None:  # RAW
        if len(stmt.operands) != 4:
            col = stmt.operands[-1].column if stmt.operands else stmt.column
            _fail(stmt.where, col, "expected RAW <command>, <type>, <motor>, <value>")
        c, t, m, v = (_operand_value(stmt, op, f, st) for op, f in
                      zip(stmt.operands, ("command", TYPE, MOTOR, VALUE), strict=True))
        return Instruction(c, t, m, v)
    cmd = stmt.command
    form = cmd.form_for(len(stmt.operands))
    if form is None:
        col = stmt.operands[-1].column if stmt.operands else stmt.column
        n = len(stmt.operands)
        _fail(stmt.where, col, f"{cmd.mnemonic} does not take {n} operand{'s' if n != 1 else ''}; "
              f"expected {cmd.usage()}")
    fields = {TYPE: 0, MOTOR: 0, VALUE: 0}
    for op, fld in zip(stmt.operands, form, strict=True):
        fields[fld] = _operand_value(stmt, op, fld, st)
    return Instruction(cmd.number, fields[TYPE], fields[MOTOR], fields[VALUE])


def _field_column(stmt: _Stmt, fld: str) -> int:
    """Column of the operand that gave field `fld` (the mnemonic's when none did)."""
    names = ("command", TYPE, MOTOR, VALUE) if stmt.command is None else \
        stmt.command.form_for(len(stmt.operands)) or ()
    for op, name in zip(stmt.operands, names, strict=False):
        if name == fld:
            return op.column
    return stmt.column


def _check_module(stmt: _Stmt, ins: Instruction, st: _State, profile: ModuleProfile) -> None:
    for finding in check_instruction(ins, profile):
        col = _field_column(stmt, finding.field)
        severity = ERROR if st.strict else WARNING
        diag = Diagnostic(stmt.where.file, stmt.where.line, col, finding.message, severity, (stmt.where.seq, col))
        (st.errors if st.strict else st.warnings).add(diag)


def _encode_all(st: _State, profile: ModuleProfile | None) -> tuple[list[Instruction], list[SourceLine | None]]:
    instructions: list[Instruction] = []
    sources: list[SourceLine | None] = []
    for stmt in st.statements:
        try:
            ins = _encode_stmt(stmt, st, profile)
        except AsmError as exc:
            st.report(exc)
            continue
        if profile is not None:
            _check_module(stmt, ins, st, profile)
        instructions.append(ins)
        sources.append(SourceLine(stmt.where.file, stmt.where.line, stmt.where.text))
    if st.append_stop:
        instructions.append(STOP)
        sources.append(None)
    return instructions, sources


def _check_size(st: _State, profile: ModuleProfile | None) -> None:
    size = len(st.statements) + int(st.append_stop)
    if profile is not None and st.origin + size > profile.program_memory:
        over = st.statements[max(0, min(profile.program_memory - st.origin, len(st.statements) - 1))]
        at = f" from address {st.origin}" if st.origin else ""
        _fail(over.where, over.column, f"program has {size} instructions{at}; "
              f"{profile.name} program memory holds {profile.program_memory}")


def _finish(st: _State, profile: ModuleProfile | None) -> Program:
    instructions, sources = _encode_all(st, profile)
    try:
        _check_size(st, profile)
    except AsmError as exc:
        st.report(exc)
    constants = {}
    for name in st.constants:
        try:
            constants[name] = _lookup(name, 1, st.constants[name][0].where, st)
        except AsmError as exc:
            st.report(exc)
    if len(st.errors):
        raise AsmError.from_collected(st.errors, st.warnings)
    labels = {name: addr for name, (addr, _) in st.labels.items()}
    return Program(instructions, labels, constants, sources, profile.name if profile else None,
                   st.filename, st.origin, st.warnings.items, st.warnings.more)


def _profile(module: str | None) -> ModuleProfile | None:
    if module is None:
        return None
    from ..modules.profile import load_profile
    try:
        return load_profile(module)
    except KeyError as exc:
        raise AsmError("<options>", 0, 0, str(exc.args[0])) from None
    except (OSError, ValueError) as exc:  # a profile file that cannot be read or used
        raise AsmError(str(module), 0, 0, f"cannot use the module profile: {exc}") from None


def assemble(source: str, *, filename: str = "<source>", include_path: Iterable[str | os.PathLike[str]] = (),
             module: str | ModuleProfile | None = None, append_stop: bool = True,
             defines: Mapping[str, int] | None = None, origin: int = 0, strict: bool = False) -> Program:
    """Assemble TMCL source text; AsmError lists every error (and the warnings so far).

    `module` ("TMCM-6212", "PD86-1180", "PD28-1021", an alias, a profile file NAME.toml or a loaded
    ModuleProfile, e.g. the profile of the module a client talks to) selects
    the bundled include files, checks that the program fits its memory (an error) and that the
    module can execute every instruction - its opcodes, motors, parameter banks and numbers, ports,
    coordinates and interrupts (`Program.warnings`; errors with `strict`). Without it the TMCM-6212
    includes are used and nothing is checked. `defines` are extra constants. `origin` is the
    program memory address the program is loaded at (labels are absolute).
    """
    if isinstance(origin, bool) or not isinstance(origin, int) or origin < 0:
        raise ValueError(f"origin must be a program memory address >= 0, not {origin!r}")
    if isinstance(source, (bytes, bytearray)):
        source = bytes(source).decode("utf-8", errors="replace")
    if not isinstance(source, str):
        raise TypeError(f"assemble() takes the source text (str or bytes), not {type(source).__name__}; "
                        "assemble_file() reads a file")
    if module is None or isinstance(module, str):
        profile, key = _profile(module), module
    else:
        profile, key = module, module.name   # the name picks the bundled includes
    st = _State(key, [Path(p) for p in include_path], append_stop, filename, origin, strict=bool(strict))
    where = _Where("<defines>", 0, "")
    for name, value in (defines or {}).items():
        st.constants[name] = [_Const(where, 0, _Expr("num", 0, value=int(value)))]
    path = Path(filename) if filename and not filename.startswith("<") else None
    if path is not None:
        st.included.add(str(path.resolve()))
    _read_text(source, filename, path, st, 0)
    return _finish(st, profile)


def assemble_file(path: str | os.PathLike[str], *, include_path: Iterable[str | os.PathLike[str]] = (),
                  module: str | ModuleProfile | None = None, append_stop: bool = True,
                  defines: Mapping[str, int] | None = None, origin: int = 0, strict: bool = False) -> Program:
    """Assemble a source file; AsmError (line 0: no position) if it cannot be read."""
    p = Path(path)
    try:
        text = read_text(p, TEXT_MAX, "program source", errors="replace")
    except InputTooLarge as exc:
        raise AsmError(str(p), 0, 0, str(exc)) from None
    except OSError as exc:
        raise AsmError(str(p), 0, 0, f"cannot read file: {exc.strerror or exc}") from None
    return assemble(text, filename=str(p), include_path=include_path, module=module,
                    append_stop=append_stop, defines=defines, origin=origin, strict=strict)
