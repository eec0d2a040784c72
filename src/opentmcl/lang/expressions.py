"""Operand expressions (docs/tmcl-assembler.md "Source format"): decimal, ``0x``/``$`` hex and
``0b`` binary literals and names with ``+ - * / % & | ^ ~ << >>`` and parentheses, C-style
division, with bounds on their size: MAX_EXPR_TOKENS numbers, names and operators, MAX_EXPR_DEPTH
levels of nesting, results within MAX_INTERMEDIATE.

`parse` reads the text into a tree, `walk` computes it with the names' values from the caller;
both report errors through a `Fail` callback at a column of the line. `evaluate` is the two
together for text outside a source file (the debugger's expressions).
"""
from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import NoReturn

from ..limits import LiteralTooLong
from ..protocol import opcodes

MAX_EXPR_DEPTH = 100
MAX_EXPR_TOKENS = 1000      # numbers, names and operators in one expression
MAX_INTERMEDIATE = 1 << 64  # expression results beyond this are errors (keeps numbers small)

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
"""A name: a label, a constant or a mnemonic."""
_BLANK_RE = re.compile(r"\s*\Z")
_TOKEN_RE = re.compile(
    r"\s*(?:(?P<num>0[xX][0-9A-Fa-f]+|\$[0-9A-Fa-f]+|0[bB][01]+|[0-9]+)"
    rf"|(?P<name>{IDENT})|(?P<op><<|>>|[-+*/%&|^~()]))"
)
_BINARY_LEVELS = (("|",), ("^",), ("&",), ("<<", ">>"), ("+", "-"), ("*", "/", "%"))

Fail = Callable[[int, str], NoReturn]
"""Raises an error at a column of the line being read."""


@dataclass(frozen=True)
class Expr:
    """A node of an expression tree; `column` is where its token starts."""

    kind: str  # num | name | un | bin
    column: int
    value: int = 0
    name: str = ""
    op: str = ""
    args: tuple[Expr, ...] = ()


def parse(text: str, col0: int, fail: Fail) -> Expr:
    """The tree of expression `text`, which starts at column `col0` of its line."""
    return _Parser(text, col0, fail).parse()


class _Parser:
    def __init__(self, text: str, col0: int, err: Fail):
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

    def parse(self) -> Expr:
        if not self.tokens:
            self.err(self.end_col, "missing operand")
        e = self._binary(0)
        if self.i < len(self.tokens):
            _, tok, col = self.tokens[self.i]
            self.err(col, f"unexpected {tok!r} in expression")
        return e

    def _peek(self) -> tuple[str, str, int] | None:
        return self.tokens[self.i] if self.i < len(self.tokens) else None

    def _binary(self, level: int) -> Expr:
        if level == len(_BINARY_LEVELS):
            return self._unary()
        left = self._binary(level + 1)
        while (t := self._peek()) and t[0] == "op" and t[1] in _BINARY_LEVELS[level]:
            self.i += 1
            right = self._binary(level + 1)
            left = Expr("bin", t[2], op=t[1], args=(left, right))
        return left

    def _unary(self) -> Expr:
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

    def _primary(self, kind: str, tok: str, col: int) -> Expr:
        if kind == "op" and tok in "+-~":
            return Expr("un", col, op=tok, args=(self._unary(),))
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
            return Expr("num", col, value=value)
        if kind == "name":
            return Expr("name", col, name=tok)
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


def walk(e: Expr, name_value: Callable[[Expr], int], fail: Fail) -> int:
    """The value of `e`, without recursion (a long chain like 1+1+...+1 is a deep tree)."""
    todo: list[tuple[Expr, bool]] = [(e, False)]
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


def _combine(e: Expr, vals: list[int], fail: Fail) -> int:
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

    return walk(parse(text, 0, fail), lambda node: lookup(node.name), fail)
