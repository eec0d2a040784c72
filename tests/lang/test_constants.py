"""Symbolic constants (TMCM-6212 manual 7.3 "Using Symbolic Constants", `Name = value`) and the
defines given from outside (`asm -D NAME=VALUE`): a definition without a value, a second definition,
a name that is also a label, a constant defined in terms of itself - each an error at its line and
column."""
from __future__ import annotations

import pytest

from opentmcl.lang.assembler import AsmError, assemble


def _error(src: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as err:
        assemble(src, **kw)
    return err.value


@pytest.mark.parametrize("src", ["X =", "X =   "])
def test_a_constant_without_an_expression(src):
    """7.3 "Using Symbolic Constants" (``Name = value``): no value is an error after the ``=``."""
    e = _error(src)
    assert (e.line, e.column, e.message) == (1, 4, "missing operand")


def test_a_constant_named_like_a_label_is_an_error_at_its_name():
    """docs/tmcl-assembler.md: "each [error] on one line as `file:line:column: message`": the
    column of a constant that repeats a label's name is that of the name."""
    e = _error("Loop: MST 0\n  Loop = 1")
    assert (e.line, e.column, e.message) == (2, 3, "'Loop' is already a label (defined at <source>:1)")


def test_a_second_definition_is_evaluated_where_it_stands():
    """docs/assumptions.md (Assembler): "a redefinition with the same value is allowed"; an
    undefined name in the second definition is an error on that line, at that name."""
    assert assemble("X = 1\nX = 2 - 1\nSAP 4, 0, X").instructions[0].value == 1
    e = _error("X = 1\nX = Y\nSAP 4, 0, X")
    assert (e.line, e.column, e.message) == (2, 5, "undefined symbol 'Y'")


def test_a_redefinition_names_the_line_of_the_first_definition():
    """docs/assumptions.md (Assembler): "a different value is an error": at the second definition,
    naming where the first one is."""
    e = _error("X = 1\n\nX = 2\nMST X")
    assert (e.line, e.column, e.message) == (3, 1, "constant 'X' redefined as 2 (was 1 at <source>:1)")


@pytest.mark.parametrize(("src", "names"), [("X = Y + 1\nY = X - 1\nSAP 4, 0, X", {"X", "Y"}),
                                            ("Self = Self + 1\nSAP 4, 0, Self", {"Self"})])
def test_a_constant_defined_in_terms_of_itself_names_the_cycle(src, names):
    """TMCM-6212 manual 7.3 "Using Symbolic Constants"; docs/assumptions.md: constants "may refer
    to constants and labels defined later" - but not, through any chain, to themselves: the
    error names every constant of the cycle, joined by '->'."""
    e = _error(src)
    head, _, chain = e.message.partition(": ")
    assert head == "constant defined in terms of itself"
    parts = chain.split(" -> ")
    assert set(parts) == names and len(parts) == len(names) + 1 and parts[0] == parts[-1]


def test_defines_are_constants_from_the_options():
    """`defines` are extra constants (`asm -D NAME=VALUE`): one the source defines again with
    another value, or uses as a label, is an error that names `<defines>` (no line: 0)."""
    assert assemble("X = 1\nMST X", defines={"X": 1}).instructions[0] == (3, 0, 1, 0)
    e = _error("X = 2\nMST X", defines={"X": 1})
    assert (e.line, e.column, e.message) == (1, 1, "constant 'X' redefined as 2 (was 1 at <defines>:0)")
    e = _error("X: MST 0", defines={"X": 1})
    assert e.message == "'X' is already a constant (defined at <defines>:0)"
