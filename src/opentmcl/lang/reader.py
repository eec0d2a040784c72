"""Reading TMCL source into statements (docs/tmcl-assembler.md "Source format"): comments, labels,
constant definitions, instructions with their operands, and the directives ``#include file`` (each
file read once, nested at most MAX_INCLUDE_DEPTH deep, each at most limits.TEXT_MAX bytes) and
``#nostop``. An error ends its line and is collected; reading goes on with the next line.
"""
from __future__ import annotations

import re
from pathlib import Path

from ..limits import TEXT_MAX, InputTooLarge, read_text
from ..protocol import opcodes
from ..protocol.opcodes import Command
from .errors import AsmError, Where, fail
from .expressions import IDENT, parse
from .includes import display_name, find_include
from .state import Operand, State, Stmt
from .symbols import define_constant, define_label

RAW = "RAW"
MAX_INCLUDE_DEPTH = 32

_LABEL_RE = re.compile(rf"\s*({IDENT})\s*:")
_CONST_RE = re.compile(rf"\s*({IDENT})\s*=(.*)\Z", re.S)
_WORD_RE = re.compile(rf"\s*({IDENT})")
_RAW_USAGE = "RAW <command>, <type>, <motor>, <value>"


def read_lines(text: str, display: str, path: Path | None, st: State, depth: int) -> None:
    """Read source `text`, shown as `display` in diagnostics, from the file `path` (None: no file)."""
    text = text.removeprefix("\ufeff")
    for lineno, raw in enumerate(text.splitlines(), 1):
        st.lines_read += 1
        where = Where(display, lineno, raw, st.lines_read)
        try:
            _read_line(raw, where, path, st, depth)
        except AsmError as exc:
            st.report(exc)


def _read_file(path: Path, display: str, st: State, where: Where | None, depth: int) -> None:
    key = str(path.resolve())
    if key in st.included:
        return
    st.included.add(key)
    try:
        text = read_text(path, TEXT_MAX, "program source", errors="replace")
    except (OSError, InputTooLarge) as exc:
        why = str(exc) if isinstance(exc, InputTooLarge) else exc.strerror or str(exc)
        if where:
            fail(where, 1, f"cannot read include file {display}: {why}")
        raise AsmError(display, 0, 0, f"cannot read file: {why}") from None
    read_lines(text, display, path, st, depth)


def strip_comment(text: str) -> str:
    cut = text.find("//")
    return text if cut < 0 else text[:cut]


def split_operands(text: str, col0: int) -> list[tuple[str, int]]:
    """Comma-separated operand texts with the 1-based column where each starts."""
    out, start = [], 0
    for i, ch in enumerate(text + ","):
        if ch == ",":
            piece = text[start:i]
            lead = len(piece) - len(piece.lstrip())
            out.append((piece.strip(), col0 + start + lead))
            start = i + 1
    return out


def _read_line(raw: str, where: Where, path: Path | None, st: State, depth: int) -> None:
    if raw.lstrip().startswith("#"):
        _directive(raw, where, path, st, depth)
        return
    line = strip_comment(raw)
    pos = _labels(line, where, st)
    rest = line[pos:]
    if not rest.strip():
        return
    if m := _CONST_RE.match(rest):
        _constant(m, pos, where, st)
        return
    _instruction(rest, pos, where, st)


def _labels(line: str, where: Where, st: State) -> int:
    """Define the labels at the start of `line`; the position after them."""
    pos = 0
    while m := _LABEL_RE.match(line, pos):
        define_label(m.group(1), m.start(1) + 1, where, st)
        pos = m.end()
    return pos


def _constant(m: re.Match[str], pos: int, where: Where, st: State) -> None:
    name = m.group(1)
    col = pos + m.start(1) + 1
    expr_col = pos + m.start(2) + 1
    try:
        expr = parse(m.group(2), expr_col, lambda c, msg: fail(where, c, msg))
    except AsmError:
        st.poisoned.add(name)  # its uses are not errors of their own
        raise
    define_constant(name, col, expr, where, st)


def _instruction(rest: str, pos: int, where: Where, st: State) -> None:
    m = _WORD_RE.match(rest)
    if not m:
        col = pos + len(rest) - len(rest.lstrip()) + 1
        fail(where, col, "expected a label, a constant definition or an instruction")
    mnemonic = m.group(1)
    col = pos + m.start(1) + 1
    after = rest[m.end():]
    if after and not after[0].isspace():
        fail(where, col + len(mnemonic), f"expected a space after {mnemonic!r}")
    command = None
    if mnemonic.upper() != RAW:
        try:
            command = opcodes.by_mnemonic(mnemonic)
        except opcodes.UnknownCommand:
            fail(where, col, f"unknown mnemonic {mnemonic!r}")
    operands = _operands(after, pos + m.end() + 1, command, where)
    st.statements.append(Stmt(where, command, mnemonic.upper(), col, operands))


def _operands(after: str, ops_col: int, command: Command | None, where: Where) -> list[Operand]:
    operands: list[Operand] = []
    if after.strip():
        for text, ocol in split_operands(after, ops_col):
            if not text:
                usage = command.usage() if command else _RAW_USAGE
                fail(where, ocol, f"empty operand; expected {usage}")
            expr = parse(text, ocol, lambda c, msg: fail(where, c, msg))
            operands.append(Operand(text, ocol, expr))
    return operands


def _directive(raw: str, where: Where, path: Path | None, st: State, depth: int) -> None:
    body = raw.lstrip()
    col = len(raw) - len(body) + 1
    m = re.match(r"#\s*(\w+)", body)
    word = m.group(1).lower() if m else ""
    if m is None or word not in ("include", "nostop"):
        fail(where, col, f"unknown directive {body.split()[0]!r}; expected #include <file> or #nostop")
    if word == "include":
        _include(body[m.end():], col, where, path, st, depth)
        return
    if strip_comment(body[m.end():]).strip():
        fail(where, col, "#nostop takes no argument")
    st.append_stop = False


def _include(arg: str, col: int, where: Where, path: Path | None, st: State, depth: int) -> None:
    name = _include_name(arg, col, where)
    if depth >= MAX_INCLUDE_DEPTH:
        fail(where, col, f"includes nested deeper than {MAX_INCLUDE_DEPTH}")
    found = find_include(name, path, st.include_path, st.module)
    if found is None:
        fail(where, col, f"include file {name!r} not found (searched the source directory, "
             f"the include path and the bundled includes)")
    _read_file(found, display_name(found), st, where, depth + 1)


def _include_name(arg: str, col: int, where: Where) -> str:
    """The file name of ``#include name``, ``#include "name"`` or ``#include <name>``."""
    arg_stripped = arg.strip()
    if arg_stripped.startswith(('"', "<")):
        close = '"' if arg_stripped[0] == '"' else ">"
        end = arg_stripped.find(close, 1)
        if end < 0:
            fail(where, col, f"missing closing {close} in #include")
        name = arg_stripped[1:end]
    else:
        name = strip_comment(arg).strip()
    if not name:
        fail(where, col, "expected a file name: #include <file>")
    return name
