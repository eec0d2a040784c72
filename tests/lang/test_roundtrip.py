"""Property tests: disassembly re-assembles to identical bytes."""
from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.lang import binfile
from opentmcl.lang.assembler import assemble
from opentmcl.lang.binfile import BinFileError, Instruction
from opentmcl.lang.disassembler import disassemble
from opentmcl.protocol.opcodes import COMMANDS, MOTOR, TYPE, VALUE

MNEMONIC_COMMANDS = [c for c in COMMANDS.values() if c.mnemonic]
INT32 = st.integers(-(2**31), 2**31 - 1)


def literal(draw, value: int) -> str:
    style = draw(st.sampled_from(["dec", "hex", "dollar", "expr"]))
    if style == "hex" and value >= 0:
        return hex(value)
    if style == "dollar" and value >= 0:
        return f"${value:X}"
    if style == "expr" and -(2**31) < value < 2**31 - 1:
        return f"({value - 1} + 1)"
    return str(value)


def mixed_case(draw, text: str) -> str:
    return "".join(c.lower() if draw(st.booleans()) else c for c in text)


@st.composite
def source_programs(draw):
    """Random TMCL source: every mnemonic command, each of its forms, symbolic and numeric types,
    labels (own line or shared), constants, comments, hex literals and mixed case."""
    n = draw(st.integers(0, 25))
    label_at = {draw(st.integers(0, n)) for _ in range(draw(st.integers(0, 4)))}
    labels = {addr: f"Lbl{addr}" for addr in label_at}
    lines = ["Const1 = 1234", "// a comment line"]
    for addr in range(n):
        cmd = draw(st.sampled_from(MNEMONIC_COMMANDS))
        form = draw(st.sampled_from(cmd.forms))
        ops = []
        for fld in form:
            if fld == TYPE and cmd.symbols and draw(st.booleans()):
                ops.append(mixed_case(draw, draw(st.sampled_from(list(cmd.symbol_table())))))
            elif fld in (TYPE, MOTOR):
                ops.append(literal(draw, draw(st.integers(0, 255))))
            elif fld == VALUE and cmd.label and labels and draw(st.booleans()):
                ops.append(labels[draw(st.sampled_from(sorted(labels)))])
            elif fld == VALUE and draw(st.integers(0, 9)) == 0:
                ops.append("Const1")
            else:
                ops.append(literal(draw, draw(INT32)))
        text = f"{mixed_case(draw, cmd.mnemonic)} {', '.join(ops)}".rstrip()
        if draw(st.booleans()):
            text += "  // comment"
        if addr in labels:
            text = f"{labels[addr]}: {text}" if draw(st.booleans()) else f"{labels[addr]}:\n    {text}"
        lines.append(text)
    if n in labels:
        lines.append(f"{labels[n]}:")
    return "\n".join(lines) + "\n"


@given(source_programs())
def test_source_disassembles_and_reassembles_identically(src):
    """disassemble(assemble(x)) re-assembles to identical bytes, with and without the label table."""
    p = assemble(src)
    image = p.image()
    assert assemble(disassemble(image)).image() == image
    assert assemble(disassemble(image, labels=p.labels, comments=False)).image() == image


def instructions():
    valid = st.builds(lambda c, t, m, v: Instruction(c.number, t, m, v), st.sampled_from(MNEMONIC_COMMANDS),
                      st.integers(0, 255), st.integers(0, 255), INT32)
    clean = st.builds(lambda c, v: Instruction(c.number, 0, 0, v), st.sampled_from(MNEMONIC_COMMANDS),
                      st.integers(-3, 40))
    anything = st.builds(Instruction, st.integers(0, 255), st.integers(0, 255), st.integers(0, 255), INT32)
    return st.one_of(valid, clean, anything)


@given(st.lists(instructions(), max_size=40), st.booleans(),
       st.sampled_from([None, "TMCM-6212", "PD86-1180", "PD28-1021"]))
def test_random_binaries_disassemble_and_reassemble_identically(program, end_with_stop, module):
    """Any sequence of 8-byte records - control commands, unknown opcodes, don't-care fields,
    jumps inside and outside the program, with or without a final STOP, with or without a module's
    parameter names - round-trips."""
    if end_with_stop:
        program = [*program, Instruction(28, 0, 0, 0)]
    image = binfile.encode(program)
    text = disassemble(image, module=module)
    assert assemble(text).image() == image


def test_given_labels_name_targets_and_bad_names_fall_back():
    """Labels from a symbol table name jump targets; names that are not identifiers (or RAW) are
    replaced by L<address>, so the text still assembles."""
    image = binfile.encode([Instruction(22, 0, 0, 1), Instruction(23, 0, 0, 0), Instruction(28)])
    text = disassemble(image, labels={"Top": 0, "Sub 1": 1}, comments=False)
    assert text == "Top:\n    JA L1\nL1:\n    CSUB Top\n"
    assert assemble(text).image() == image
    assert disassemble(binfile.encode([]), comments=False) == "#nostop\n"


def test_disassembler_takes_the_first_given_label_by_name():
    """Two names for one address: the first in alphabetical order is used, whatever the order of
    the mapping."""
    prog = [(22, 0, 0, 0), (28, 0, 0, 0)]  # JA 0 (3.6.17 "JA <label>"), STOP
    for labels in ({"b": 0, "a": 0}, {"a": 0, "b": 0}):
        assert disassemble(prog, labels=labels, comments=False) == "a:\n    JA a\n"


def test_generated_label_does_not_repeat_a_given_one():
    """A jump target without a given name gets ``L<address>``; when a given label already has
    that name (``L1`` at address 0 here), ``_`` is appended, and the text re-assembles to the same
    records."""
    prog = [(22, 0, 0, 1), (3, 0, 0, 0), (28, 0, 0, 0)]  # JA 1, MST 0, STOP
    text = disassemble(prog, labels={"L1": 0}, comments=False)
    assert text == "L1:\n    JA L1_\nL1_:\n    MST 0\n"
    assert assemble(text).instructions == prog


def test_module_names_in_disassembly():
    """With a module, parameter, interrupt and motor numbers come out as the bundled names
    (TMCM-6212 7.3 style: SAP APMaxPositioningSpeed, Motor0, ...; 3.5.6.4: EI TI_GLOBAL)."""
    prog = assemble("SAP 4, 0, 51200\nSGP 0, 3, 1000\nSGP 7, 2, 5\nEI 255\nVECT 0, 0\nWAIT POS, 1, 0")
    text = disassemble(prog.image(), module="TMCM-6212", comments=False)
    assert text.splitlines() == [
        "#include tmcm6212.inc", "L0:", "    SAP APMaxPositioningSpeed, Motor0, 51200",
        "    SGP GPTimer0Period, 3, 1000", "    SGP 7, 2, 5", "    EI TI_GLOBAL", "    VECT TI_TIMER0, L0",
        "    WAIT POS, 1, 0"]
    assert assemble(text).image() == prog.image()


def test_disassemble_refuses_what_is_not_a_program():
    """Bad input is a clear error, not garbage source: a str is not a binary image (it used to
    come out as `RAW a, 0, 0, 0` lines), and list entries must be 4 integers in the fields'
    ranges (binary format: command, type and motor/bank are single bytes)."""
    with pytest.raises(TypeError, match="not str"):
        disassemble("abc")
    with pytest.raises(BinFileError, match="instruction 1"):
        disassemble([(28, 0, 0, 0), (1, 2)])
    with pytest.raises(BinFileError, match="command must be 0..255"):
        disassemble([(300, 0, 0, 0)])
    assert "ROR 0, 5" in disassemble([(1, 0, 0, 5)])


def test_assemble_takes_text_or_bytes_only():
    """Source bytes are read as UTF-8 text; anything else is a TypeError that says what is expected."""
    assert assemble(b"ROR 0, 5\n").image() == assemble("ROR 0, 5\n").image()
    with pytest.raises(TypeError, match="source text"):
        assemble(None)
