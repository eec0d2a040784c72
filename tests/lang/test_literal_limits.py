"""Issue 11 problem 4: "a number literal of 5000 digits gives an untyped ValueError".

Literal forms (docs/tmcl-assembler.md): "Numbers: `1000`, `-5000`, `0x1F40`, `$1F40`, `0b1010`";
values are 32 bit (TMCM-6212 manual 3.1: "Value (MSB first!)" - four bytes). The longest literal
of a 32-bit value is 0b followed by 32 binary digits, so a literal has at most 32 digits after its
sign and prefix (opentmcl.limits.LITERAL_DIGITS_MAX); the 33rd digit is refused with a typed,
one-line error in the assembler, the ASCII protocol parser, `opentmcl send` and the TMC4210
calculator (`opentmcl tmc4210`), never with int()'s digit-limit ValueError.
"""
import subprocess
import sys

import pytest

from opentmcl.lang.assembler import AsmError, assemble
from opentmcl.protocol import ascii as codec
from opentmcl.protocol.status import Status

HUGE = "1" * 5000
# the longest valid form of 0xFFFFFFFF in each notation: (prefix, 32 digits)
LONGEST = {"binary": ("0b", "1" * 32), "hex $": ("$", "0" * 24 + "FFFFFFFF"),
           "hex 0x": ("0x", "0" * 24 + "ffffffff"), "decimal": ("", "0" * 22 + "4294967295")}


def value_of(literal: str) -> int:
    return assemble(f"MVP ABS, 0, {literal}", append_stop=False).instructions[0].value


@pytest.mark.parametrize("form", sorted(LONGEST))
def test_assembler_longest_literal_and_one_digit_more(form):
    """32 digits give the value (0xFFFFFFFF is -1 as a signed 32-bit field); 33 are refused."""
    prefix, digits = LONGEST[form]
    assert value_of(prefix + digits) == -1
    longer = prefix + "0" + digits    # a leading zero more: same value, 33 digits
    with pytest.raises(AsmError, match="33 digits is too long"):
        value_of(longer)


def test_assembler_5000_digits_is_a_short_asm_error():
    with pytest.raises(AsmError) as info:
        assemble(f"MVP ABS, 0, {HUGE}\nSTOP\n", filename="big.tmc")
    msg = str(info.value)
    assert msg.startswith("big.tmc:1:13: ") and "5000 digits" in msg and len(msg) < 200


def test_ascii_parser_refuses_long_literals_with_a_status():
    """PD86-1180 manual 4.5.2: "After executing the command the module sends back a reply ... the
    status code as a decimal number". A literal that is too long is AsciiError with status 4
    (invalid value); the 32-digit edge is accepted."""
    cmd = codec.parse_command("AMVP ABS, 0, " + "".join(LONGEST["binary"]))
    assert cmd.value == -1
    for text in ("AMVP ABS, 0, " + HUGE, "AMVP ABS, 0, 0" + LONGEST["decimal"][1], "ASAP 4, " + HUGE + ", 1"):
        with pytest.raises(codec.AsciiError) as info:
            codec.parse_command(text)
        assert info.value.status == Status.INVALID_VALUE and len(str(info.value)) < 200
    with pytest.raises(codec.AsciiError):
        codec.parse_reply("BA 100 " + HUGE)
    assert codec.parse_reply("BA 100 -" + "0" * 22 + "2147483648").value == -(2 ** 31)


def cli(*args):
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], capture_output=True, text=True,
                          timeout=60)


def one_short_line(res) -> str:
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1 and "Traceback" not in res.stderr, res.stderr[:300]
    assert len(lines[0]) < 250, lines[0][:300]
    return lines[0]


def test_send_refuses_5000_digits_in_one_short_line():
    """`opentmcl send` in mnemonic and numeric form; exit 2 (bad input), not rc 1 with a ValueError."""
    assert "too long" in one_short_line(cli("send", f"MVP ABS, 0, {HUGE}", "--to", "sim://TMCM-6212"))
    assert "too long" in one_short_line(cli("send", f"{HUGE}, 0, 0, 0", "--to", "sim://TMCM-6212"))
    assert "too long" in one_short_line(cli("asm", "-D", f"X={HUGE}", "x.tmc"))


def test_calculator_literal_edge():
    """`opentmcl tmc4210 convert -v V -p PULSE_DIV` (datasheet velocity register): 32 digits are a
    number, 33 and 5000 are a short usage error."""
    ok = cli("tmc4210", "convert", "-v", "0" * 29 + "100", "-p", "0")
    assert ok.returncode == 0, ok.stderr
    assert "too long" in one_short_line(cli("tmc4210", "convert", "-v", "0" * 30 + "100", "-p", "0"))
    assert "too long" in one_short_line(cli("tmc4210", "convert", "-v", HUGE, "-p", "0"))
    assert "finite" in one_short_line(cli("tmc4210", "convert", "--hz", HUGE, "-p", "0"))
