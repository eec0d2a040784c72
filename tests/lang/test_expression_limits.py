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

from opentmcl.lang.assembler import MAX_CONSTANT_DEPTH, MAX_EXPR_TOKENS, AsmError, assemble


def chain(terms: int) -> str:
    """1+1+...+1 with `terms` ones: 2 * terms - 1 tokens."""
    return "+".join(["1"] * terms)


def value(source: str) -> int:
    return assemble(source).instructions[0].value


def test_the_bounds_are_the_documented_ones():
    assert (MAX_EXPR_TOKENS, MAX_CONSTANT_DEPTH) == (1000, 100)


def test_longest_expression_is_computed_one_token_more_is_an_error():
    """'-' and 500 ones joined by 499 '+': exactly 1000 tokens, value -1 + 499 (a left-deep tree
    500 levels deep: computed without recursion)."""
    assert value(f"MVP ABS, 0, -{chain(500)}") == 498
    with pytest.raises(AsmError, match="longer than 1000"):
        assemble(f"MVP ABS, 0, {chain(501)}")          # 1001 tokens


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
