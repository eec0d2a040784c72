"""One direct-mode instruction from text (lang/direct.py), as `opentmcl send` and the dashboard
console read it - tested here in-process, so that the mutation run (which leaves out the CLI
subprocess tests and tests/web) reaches it (docs/mutation.md).

TMCM-6212 manual 3.6: an instruction is written as in TMCL source (``MVP ABS, 0, 1000``);
3.6.36 "TMCL Control Commands ... only have opcodes, but no mnemonics", so they are written as
up to four numbers ``COMMAND, TYPE, MOTOR, VALUE``.
"""
from __future__ import annotations

import pytest

from opentmcl.lang.direct import InstructionError, parse_direct


@pytest.mark.parametrize(("text", "fields"), [
    ("MVP ABS, 0, 1000", (4, 0, 0, 1000)),      # the chapter 7 example (7.6)
    ("GAP 1, 0", (6, 1, 0, 0)),                 # 3.6.6 "Mnemonic: GAP 1, 0"
    ("SAP 4, 0, 51200*2", (5, 4, 0, 102400)),   # an expression, as in TMCL source
    ("mvp rel, 0, -10000", (4, 1, 0, -10000)),  # 3.6.4 "MVP REL, 0, -10000", lower case
])
def test_mnemonic_forms_are_assembled(text, fields):
    """3.6: the mnemonic form of an instruction, with the command's symbolic type names."""
    assert parse_direct(text) == fields


@pytest.mark.parametrize(("text", "fields"), [
    ("136, 0, 0, 0", (136, 0, 0, 0)),   # 136 - get firmware version, type 0: string format
    ("136,1,0,0", (136, 1, 0, 0)),      # commas without blanks
    ("129 1 0 5", (129, 1, 0, 5)),      # 129 type 1: "from specific address", blanks only
    ("0x88, 1", (136, 1, 0, 0)),        # hexadecimal literal
    ("$83", (131, 0, 0, 0)),            # one number: the others are 0
    ("128, 0", (128, 0, 0, 0)),         # two of four
])
def test_control_commands_as_numbers(text, fields):
    """3.6.36: control commands have opcodes but no mnemonics: up to four numbers, the missing
    ones 0 ("0 (don't care)")."""
    assert parse_direct(text) == fields


def test_four_numbers_are_the_most():
    """COMMAND, TYPE, MOTOR, VALUE: four numbers are accepted, a fifth is an error naming the text."""
    assert parse_direct("137, 0, 0, 1234") == (137, 0, 0, 1234)
    with pytest.raises(InstructionError, match=r"^'137, 0, 0, 1234, 0': expected COMMAND, TYPE, MOTOR, VALUE as numbers$"):
        parse_direct("137, 0, 0, 1234, 0")


def test_a_word_after_a_number_is_an_error():
    with pytest.raises(InstructionError, match=r"^'136, 0, x': expected COMMAND, TYPE, MOTOR, VALUE as numbers$"):
        parse_direct("136, 0, x")


@pytest.mark.parametrize("text", ["", "   ", "// only a comment", "Label:"])
def test_no_instruction_is_an_error(text):
    """Text without an instruction (nothing, a comment, a label only) names itself."""
    with pytest.raises(InstructionError, match=rf"^{text!r}: expected one instruction$"):
        parse_direct(text)


def test_two_lines_are_refused():
    with pytest.raises(InstructionError, match=r"^'MST 0\\nMST 1': one instruction per argument$"):
        parse_direct("MST 0\nMST 1")


def test_assembler_errors_name_the_text_and_the_send_source():
    """An assembler error carries the text; where it names a source, that is ``<send>``."""
    with pytest.raises(InstructionError, match=r"^'FOO 1': unknown mnemonic 'FOO'$"):
        parse_direct("FOO 1")
    with pytest.raises(InstructionError, match=r"^'L: L: MST 0': label 'L' already defined at <send>:1$"):
        parse_direct("L: L: MST 0")


def test_literal_of_33_digits_is_an_error_in_both_forms():
    """docs/tmcl-assembler.md: "A number has at most 32 digits ... The same rule holds for
    `opentmcl send`": 32 digits are read, 33 are an InstructionError (not a traceback)."""
    assert parse_direct("0b" + "0" * 24 + "10001000") == (136, 0, 0, 0)
    for text in ("0b" + "0" * 25 + "10001000", "GAP 1, " + "0" * 33):
        with pytest.raises(InstructionError, match="number literal of 33 digits is too long"):
            parse_direct(text)
