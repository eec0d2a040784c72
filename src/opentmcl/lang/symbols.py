"""Labels and constants (docs/tmcl-assembler.md "Source format"; TMCM-6212 manual 7.3 "Using
Symbolic Constants"): their definitions, and the value of a name in an operand.

A label is the address of the next instruction. A constant is an expression, computed when it is
first used; every definition of it must give the same value, and one defined through more than
MAX_CONSTANT_DEPTH levels of other constants, or through itself, is an error. A constant whose
definition failed is "poisoned": its uses are not errors of their own.
"""
from __future__ import annotations

from .errors import AsmError, Cascade, Where, fail
from .expressions import Expr, walk
from .state import Const, State

MAX_CONSTANT_DEPTH = 100    # constants defined through constants, this many levels deep


def define_label(name: str, col: int, where: Where, st: State) -> None:
    if name in st.labels:
        first = st.labels[name][1]
        fail(where, col, f"label {name!r} already defined at {first.file}:{first.line}")
    if name in st.constants:
        first = st.constants[name][0].where
        fail(where, col, f"{name!r} is already a constant (defined at {first.file}:{first.line})")
    st.labels[name] = (st.origin + len(st.statements), where)


def define_constant(name: str, col: int, expr: Expr, where: Where, st: State) -> None:
    if name in st.labels:
        first = st.labels[name][1]
        fail(where, col, f"{name!r} is already a label (defined at {first.file}:{first.line})")
    st.constants.setdefault(name, []).append(Const(where, col, expr))


def _names_like(name: str, st: State) -> list[str]:
    low = name.lower()
    return sorted(n for n in (*st.labels, *st.constants) if n.lower() == low and n != name)


def lookup(name: str, col: int, where: Where, st: State) -> int:
    """The value of the label or constant `name`, used at `col` of the line `where`."""
    if name in st.labels:
        return st.labels[name][0]
    if name in st.values:
        return st.values[name]
    if name in st.poisoned:
        raise Cascade(where.file, where.line, col, f"{name!r} has an error in its definition")
    if name in st.constants:
        return _resolve(name, col, where, st)
    hint = _names_like(name, st)
    extra = f" (names are case-sensitive; did you mean {hint[0]!r}?)" if hint else ""
    fail(where, col, f"undefined symbol {name!r}{extra}")


def _resolve(name: str, col: int, where: Where, st: State) -> int:
    """The value of constant `name` (every definition must agree); an error poisons it."""
    try:
        return _resolve_checked(name, col, where, st)
    except AsmError:
        st.poisoned.add(name)
        raise


def _resolve_checked(name: str, col: int, where: Where, st: State) -> int:
    if name in st.resolving:
        chain = " -> ".join(st.resolving[st.resolving.index(name):] + [name])
        fail(where, col, f"constant defined in terms of itself: {chain}")
    if len(st.resolving) > MAX_CONSTANT_DEPTH:
        fail(where, col, f"constant {st.resolving[0]!r} is defined through more than "
                         f"{MAX_CONSTANT_DEPTH} levels of other constants (down to {name!r})")
    st.resolving.append(name)
    try:
        defs = st.constants[name]
        first = value_of(defs[0].expr, defs[0].where, st)
        for other in defs[1:]:
            v = value_of(other.expr, other.where, st)
            if v != first:
                fail(other.where, other.column,
                     f"constant {name!r} redefined as {v} (was {first} at "
                     f"{defs[0].where.file}:{defs[0].where.line})")
    finally:
        st.resolving.pop()
    st.values[name] = first
    return first


def value_of(e: Expr, where: Where, st: State) -> int:
    """The value of expression `e` of the line `where`, its names looked up in `st`."""
    return walk(e, lambda node: lookup(node.name, node.column, where, st), lambda c, msg: fail(where, c, msg))
