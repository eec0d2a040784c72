"""Operand expressions (docs/tmcl-assembler.md "Source format"; docs/assumptions.md (Assembler): "C
integer semantics"): what may start an expression, every operator level inside parentheses, `/` and
`%` with negative operands."""
from __future__ import annotations

import pytest

from opentmcl.lang.assembler import AsmError, assemble


def _error(src: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as err:
        assemble(src, **kw)
    return err.value


@pytest.mark.parametrize(("operand", "message"), [("*2", "unexpected '*' in expression"),
                                                  (")", "unexpected ')' in expression")])
def test_an_operator_that_cannot_start_an_expression(operand, message):
    """Only ``+ - ~`` and ``(`` may start an expression (docs/tmcl-assembler.md "Source format")."""
    e = _error(f"SAP 4, 0, {operand}")
    assert (e.column, e.message) == (11, message)


@pytest.mark.parametrize(("expr", "value"), [("(1|2)", 3), ("(6^3)", 5), ("-(1|2)", -3), ("(1|2)*2", 6)])
def test_parentheses_hold_every_operator_level(expr, value):
    """C semantics: inside parentheses the lowest-precedence operators (``|``, ``^``) are read too."""
    assert assemble(f"SAP 4, 0, {expr}").instructions[0].value == value


@pytest.mark.parametrize(("expr", "value"), [("-7 % 3", -1), ("7 % -3", 1), ("7 % 3", 1),
                                             ("-7 / 2", -3), ("7 / -2", -3), ("-7 / -2", 3)])
def test_division_and_remainder_follow_c(expr, value):
    """docs/assumptions.md (Assembler): "C integer semantics (`/` truncates toward zero, `%` takes
    the dividend's sign)"."""
    assert assemble(f"SAP 4, 0, {expr}").instructions[0].value == value
