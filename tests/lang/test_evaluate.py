"""`lang.assembler.evaluate`: the assembler's operand expressions with names from the caller (the
debugger's `print`, issue 32 item 7). TMCM-6212 manual 7.3 "Using Symbolic Constants": names
and arithmetic in operands."""
from __future__ import annotations

import re

import pytest

from opentmcl.lang.assembler import ExpressionError, assemble, evaluate


@pytest.mark.parametrize(("text", "value"), [
    ("2 + 3 * 4", 14), ("(2 + 3) * 4", 20), ("-7 / 2", -3), ("7 % -4", 3), ("1 << 4 | 1", 17),
    ("~0 & 0xFF", 255), ("$10 + 0b11", 19), ("speed * 2 - Base", 51200 * 2 - 100),
])
def test_evaluate_agrees_with_the_assembler(text, value):
    """The same text as an SAP operand assembles to the same value (one expression syntax)."""
    names = {"speed": 51200, "Base": 100}
    assert evaluate(text, names.__getitem__) == value
    source = "".join(f"{k} = {v}\n" for k, v in names.items()) + f"SAP 4, 0, {text}\n"
    assert assemble(source, append_stop=False).instructions[0][3] == value


def test_each_name_goes_to_the_lookup_and_its_error_through():
    asked: list[str] = []

    def lookup(name: str) -> int:
        asked.append(name)
        if name == "nope":
            raise KeyError(name)
        return 1

    assert evaluate("a + b * a", lookup) == 2 and asked == ["a", "b", "a"]
    with pytest.raises(KeyError):
        evaluate("a + nope", lookup)


@pytest.mark.parametrize(("text", "column", "message"), [
    ("", 0, "missing operand"), ("1 +", 3, "expression ends too early"), ("1/0", 1, "division by zero"),
    ("(1", 2, "missing ')'"), ("1 ? 2", 2, "unexpected character '?'"), ("1 << 64", 2, "shift count 64"),
])
def test_text_that_is_no_expression_is_an_expression_error_with_its_column(text, column, message):
    with pytest.raises(ExpressionError, match=re.escape(message)) as err:
        evaluate(text, lambda name: 0)
    assert err.value.column == column and isinstance(err.value, ValueError)
