"""Long and deep expressions (house rules: bad input is a typed one-line error, never a crash).

The manuals give operands as plain numbers (TMCM-6212 manual 3.6: ``MVP ABS, 0, 1000``); the
expressions and constants of our assembler are our extension (docs/tmcl-assembler.md), with
documented bounds: at most MAX_EXPR_TOKENS numbers, names and operators in one expression, and
constants defined through at most MAX_CONSTANT_DEPTH levels of other constants. Up to the bounds
the value is computed; one more is an `AsmError` (exit 2 in the CLI), not a RecursionError."""
from __future__ import annotations

import subprocess
import sys

import pytest

from opentmcl.lang.assembler import (
    MAX_CONSTANT_DEPTH,
    MAX_EXPR_DEPTH,
    MAX_EXPR_TOKENS,
    MAX_INCLUDE_DEPTH,
    MAX_INTERMEDIATE,
    AsmError,
    assemble,
    assemble_file,
)


def chain(terms: int) -> str:
    """1+1+...+1 with `terms` ones: 2 * terms - 1 tokens."""
    return "+".join(["1"] * terms)


def value(source: str) -> int:
    return assemble(source).instructions[0].value


def _error(src: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as err:
        assemble(src, **kw)
    return err.value


def test_the_bounds_are_the_documented_ones():
    assert (MAX_EXPR_TOKENS, MAX_CONSTANT_DEPTH) == (1000, 100)
    assert (MAX_EXPR_DEPTH, MAX_INCLUDE_DEPTH, MAX_INTERMEDIATE) == (100, 32, 2 ** 64)


@pytest.mark.parametrize("prefix", ["(", "-", "~", "+"])
def test_deepest_nesting_is_computed_one_level_more_is_an_error(prefix):
    """docs/assumptions.md "Expression bounds": 100 levels of nesting. A number under 99 prefix
    operators or parentheses is 100 levels (the number is the innermost); one more is refused at
    the number's column."""
    def nested(n: int) -> str:
        return prefix * n + "5" + (")" * n if prefix == "(" else "")
    assert value(f"MVP ABS, 0, {nested(99)}") == {"(": 5, "+": 5, "-": -5, "~": ~5}[prefix]  # 99 is odd
    with pytest.raises(AsmError, match="nested deeper than 100 levels") as info:
        assemble(f"MVP ABS, 0, {nested(100)}")
    assert info.value.column == len("MVP ABS, 0, ") + 101


@pytest.mark.parametrize("op", ["<<", ">>"])
def test_shift_count_edges(op):
    """docs/assumptions.md "Expression bounds": a shift count is 0..63; 64 and -1 are refused."""
    assert value(f"MVP ABS, 0, (1 << 31) {op} 0") == -(2 ** 31)
    assert assemble(f"X = 1 {op} 63\nSTOP").constants["X"] == (2 ** 63 if op == "<<" else 0)
    for count in ("64", "-1"):
        with pytest.raises(AsmError, match=rf"shift count {count} out of range 0\.\.63"):
            assemble(f"X = 1 {op} {count}\nSTOP")


def test_intermediate_values_up_to_64_bits():
    """docs/assumptions.md "Expression bounds": results beyond 64 bits are errors - +-2^64 is the
    last value computed, one more either way is refused."""
    top = "(1 << 63) * 2"
    assert assemble(f"X = {top}\nY = -{top}\nSTOP").constants == {"X": 2 ** 64, "Y": -(2 ** 64)}
    for text in (f"{top} + 1", f"-{top} - 1"):
        with pytest.raises(AsmError, match="more than 64 bits"):
            assemble(f"X = {text}\nSTOP")


def include_chain(tmp_path, depth: int):
    """main.tmc includes f1.inc, which includes f2.inc, ... down to f<depth>.inc."""
    for i in range(1, depth + 1):
        nxt = f"#include f{i + 1}.inc\n" if i < depth else "Deepest = 1\n"
        (tmp_path / f"f{i}.inc").write_text(nxt)
    (tmp_path / "main.tmc").write_text("#include f1.inc\nMVP ABS, 0, Deepest\n")
    return tmp_path / "main.tmc"


def test_deepest_include_nesting_one_more_is_an_error(tmp_path):
    """docs/assumptions.md "#include": nesting limit 32 - 32 files included inside each other are
    read; the 33rd #include is refused on its own line."""
    assert assemble_file(include_chain(tmp_path, 32)).instructions[0].value == 1
    with pytest.raises(AsmError, match="includes nested deeper than 32") as info:
        assemble_file(include_chain(tmp_path, 33))
    assert info.value.file.endswith("f32.inc") and info.value.line == 1


def test_longest_expression_is_computed_one_token_more_is_an_error():
    """'-' and 500 ones joined by 499 '+': exactly 1000 tokens, value -1 + 499 (a left-deep tree
    500 levels deep: computed without recursion)."""
    assert value(f"MVP ABS, 0, -{chain(500)}") == 498
    with pytest.raises(AsmError, match="longer than 1000"):
        assemble(f"MVP ABS, 0, {chain(501)}")          # 1001 tokens


def test_an_expression_one_token_too_long_is_an_error_at_the_limit_not_before():
    """docs/assumptions.md "Expression bounds": "1000 tokens per expression"; docs/tmcl-assembler.md:
    beyond that "the error names the line and column". '1+1+...': the 1000th token is the last
    one allowed; the error points at the place where the limit is reached (the 1000th or the
    1001st token), not at an earlier token and not without a column."""
    assert MAX_EXPR_TOKENS == 1000
    head = "MVP ABS, 0, "
    ok = "~" + "+".join(["1"] * 500)                     # 1000 tokens: ~1 + 499 ones
    assert assemble(head + ok).instructions[0].value == 497
    text = "+".join(["1"] * 501)                         # 1001 tokens, one character each
    col_of = {k: len(head) + k for k in (999, 1000, 1001)}   # 1-based column of the k-th token
    assert text[col_of[1001] - len(head) - 1] == "1" and len(text) == 1001
    e = _error(f"MST 0\n{head}{text}")
    assert e.message == "expression longer than 1000 numbers, names and operators"
    assert e.line == 2
    assert isinstance(e.column, int) and col_of[999] < e.column <= col_of[1001]


def constants(depth: int) -> str:
    """C0 = 1 and C1..C`depth`, each the one before + 1; MVP ABS uses the last one first."""
    lines = ["C0 = 1"] + [f"C{i} = C{i - 1} + 1" for i in range(1, depth + 1)]
    return "\n".join(lines) + f"\nMVP ABS, 0, C{depth}\n"


def test_deepest_constant_chain_is_computed_one_level_more_is_an_error():
    """C100 is defined through 100 other constants (C99..C0): the last valid depth."""
    assert value(constants(100)) == 101
    with pytest.raises(AsmError, match="more than 100 levels"):
        assemble(constants(101))


def cli(*args: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], cwd=cwd, capture_output=True,
                          text=True, timeout=120)


def one_line(result: subprocess.CompletedProcess) -> str:
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and "Traceback" not in result.stderr, result.stderr[:300]
    assert "internal error" not in lines[0] and len(lines[0]) < 250, lines[0][:300]
    return lines[0]


def test_asm_100000_terms_is_a_one_line_error_and_writes_nothing(tmp_path):
    """`opentmcl asm` on ``MVP ABS, 0, 1+1+...`` with 100000 terms (a RecursionError before)."""
    src = tmp_path / "deep.tmc"
    src.write_text(f"MVP ABS, 0, {chain(100_000)}\n")
    line = one_line(cli("asm", str(src), "-o", str(tmp_path / "deep.bin"), cwd=tmp_path))
    assert "deep.tmc:1:" in line and "longer than 1000" in line
    assert not (tmp_path / "deep.bin").exists()


def test_asm_deep_constant_chain_is_a_one_line_error(tmp_path):
    src = tmp_path / "chain.tmc"
    src.write_text(constants(3000))
    assert "more than 100 levels" in one_line(cli("asm", str(src), "-o", str(tmp_path / "c.bin"), cwd=tmp_path))


def test_send_long_expression(tmp_path):
    """`opentmcl send` parses with the assembler: 400 terms reach the module (value 400, read
    back with GAP 0), 20000 terms are a one-line error."""
    result = cli("send", f"SAP 0, 0, {chain(400)}", "GAP 0, 0", "--to", "sim://TMCM-6212", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split()[-1] == "400"
    assert "longer than 1000" in one_line(cli("send", f"MVP ABS, 0, {chain(20_000)}", "--to", "sim://TMCM-6212",
                                              cwd=tmp_path))
