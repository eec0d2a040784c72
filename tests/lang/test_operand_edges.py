"""The last valid and the first invalid value of every operand range the assembler checks (issue 12).

TMCM-6212 manual 3.1 "Binary Command Format": "Every command consists of a one-byte command field,
a one-byte type field, a one-byte motor/bank field and a four-byte value field." The operands of
3.4.1 "TMCL Commands" (<parameter>, <motor number>, <bank number>, <coordinate number>, <interrupt
number>, <jump address>, <value>) land in those fields, so the assembler accepts what the field can
hold - 0..255 for the byte fields, -2^31..2^32-1 for the value (docs/assumptions.md "Assembler /
disassembler": an unsigned 32-bit literal such as 0xFFFFFFFF is stored as its signed 32-bit
pattern) - and leaves the module's own narrower ranges (SCO "<coordinate number> 0...20", "<motor
number> 0...5", 3.6.22) to the module, which answers them with status 4.
"""
from __future__ import annotations

import pytest

from opentmcl.lang.assembler import AsmError, assemble
from opentmcl.lang.disassembler import disassemble
from opentmcl.modules.profile import load_profile, module_names

BYTE_MAX = 0xFF
INT32_MIN = -(2 ** 31)
UINT32_MAX = 2 ** 32 - 1


def one(src: str) -> tuple[int, int, int, int]:
    """The single instruction `src` assembles to."""
    (ins,) = assemble(src, append_stop=False).instructions
    return tuple(ins)


def refused(src: str, **kw: object) -> AsmError:
    with pytest.raises(AsmError) as info:
        assemble(src, filename="t.tmc", **kw)
    return info.value


# --- one-byte fields: type, motor/bank, command ----------------------------------------------

BYTE_OPERANDS = [
    # (what, source with {} for the operand, field index in (command, type, motor, value), message)
    ("SAP <parameter>", "SAP {}, 0, 1", 1, "type operand must be 0..255"),
    ("SAP <motor number>", "SAP 4, {}, 1", 2, "motor/bank operand must be 0..255"),
    ("SGP <bank number>", "SGP 0, {}, 1", 2, "motor/bank operand must be 0..255"),
    ("SCO <coordinate number>", "SCO {}, 0, 1", 1, "type operand must be 0..255"),
    ("GCO <coordinate number>", "GCO {}, 0", 1, "type operand must be 0..255"),
    ("CCO <coordinate number>", "CCO {}, 0", 1, "type operand must be 0..255"),
    ("ACO <coordinate number>", "ACO {}, 0", 1, "type operand must be 0..255"),
    ("EI <interrupt number>", "EI {}", 1, "type operand must be 0..255"),
    ("VECT <interrupt number>", "VECT {}, 0", 1, "type operand must be 0..255"),
    ("GIO <bank number>", "GIO 0, {}", 2, "motor/bank operand must be 0..255"),
    ("RAW command", "RAW {}, 0, 0, 0", 0, "command operand must be 0..255"),
    ("RAW type", "RAW 5, {}, 0, 0", 1, "type operand must be 0..255"),
    ("RAW motor", "RAW 5, 0, {}, 0", 2, "motor/bank operand must be 0..255"),
]


@pytest.mark.parametrize(("what", "src", "index", "message"), BYTE_OPERANDS, ids=[b[0] for b in BYTE_OPERANDS])
def test_byte_operand_last_valid_and_first_invalid(what, src, index, message):
    """TMCM-6212 3.1: "a one-byte command field, a one-byte type field, a one-byte motor/bank
    field": 0 and 255 (also as $FF, 0xFF, 0b11111111) are the field; 256 and -1 are refused at the
    operand's column."""
    for literal in ("0", "255", "$FF", "0xFF", "0b11111111"):
        assert one(src.format(literal))[index] == int(literal.replace("$", "0x"), 0)
    column = src.index("{}") + 1
    for bad in ("256", "-1", "0x100"):
        e = refused(src.format(bad))
        assert message in e.message and e.column == column, str(e)
        assert f"got {int(bad, 0)}" in e.message


def test_coordinate_and_motor_numbers_beyond_the_module_range_are_the_modules_business():
    """TMCM-6212 3.6.22 SCO: "<coordinate number> 0...20 | <motor number> 0...5" - the assembler
    writes what fits the byte field (21 and 6 included, as TMCL-IDE does); the module answers them
    with status 4 when the program runs."""
    assert one("SCO 20, 5, 1") == (30, 20, 5, 1)
    assert one("SCO 21, 6, 1") == (30, 21, 6, 1)


# --- the four-byte value field -------------------------------------------------------------------

@pytest.mark.parametrize(("literal", "stored"), [
    ("-2147483648", INT32_MIN),                # the smallest signed 32-bit value
    ("2147483647", 2 ** 31 - 1),               # the largest signed one
    ("2147483648", INT32_MIN),                 # unsigned from here on: the same 32 bits
    ("4294967295", -1),                        # the largest unsigned 32-bit literal
    ("0xFFFFFFFF", -1),
    ("$FFFFFFFF", -1),
    ("0b" + "1" * 32, -1),
    ("0x80000000", INT32_MIN),
    ("-(1 << 31)", INT32_MIN),
    ("(1 << 32) - 1", -1),
])
def test_value_operand_last_valid(literal, stored):
    """TMCM-6212 3.1: "4 | Value (MSB first!)"; SAP (3.6.5) "<value>", MVP (3.6.4) "<position>
    $-2^{31} \\dots 2^{31} - 1$": -2^31..2^31-1 and the unsigned 32-bit literals up to 2^32-1, stored
    as the signed 32-bit value of the same four bytes."""
    assert one(f"SAP 4, 0, {literal}")[3] == stored
    assert one(f"MVP ABS, 0, {literal}")[3] == stored
    assert one(f"RAW 5, 4, 0, {literal}")[3] == stored


@pytest.mark.parametrize("literal", ["-2147483649", "4294967296", "0x100000000", "$100000000",
                                     "(1 << 32)", "-(1 << 31) - 1"])
def test_value_operand_first_invalid(literal):
    """One beyond the four-byte value field on either side (-2^31 - 1, 2^32) is refused at the
    operand's column, never wrapped into 32 bits."""
    for src in (f"SAP 4, 0, {literal}", f"RAW 5, 4, 0, {literal}", f"JA {literal}"):
        e = refused(src)
        assert "value operand out of 32-bit range" in e.message and e.column == src.index(literal) + 1, str(e)


def test_jump_address_is_a_value_operand():
    """TMCM-6212 3.6.19 JA: "<jump address>" in the value field - a label or any 32-bit number."""
    assert one("JA 4294967295") == (22, 0, 0, -1)
    assert one("JA -2147483648") == (22, 0, 0, INT32_MIN)


# --- program memory size, per module profile ----------------------------------------------------

MEMORY = {name: load_profile(name).program_memory for name in module_names()}
"""TMCM-6212 chapter 1: "program memory (non volatile) for up to 6144 TMCL commands"; PD86-1180
chapter 1: "Program memory (non volatile) for up to 2048 TMCL commands"; PD28-1021: 2048 (not in
its partial manual; docs/assumptions.md "PD28-1021 profile")."""


def test_memory_sizes_are_the_manuals():
    assert MEMORY == {"TMCM-6212": 6144, "PD86-1180": 2048, "PD28-1021": 2048}


def program(count: int) -> str:
    return "".join(f"ROL 0, {i}\n" for i in range(count))


@pytest.mark.parametrize("module", sorted(MEMORY))
def test_program_fills_memory_to_the_last_address(module):
    """A program of exactly the module's memory size fits: with #nostop its last instruction lands
    at the last address (size - 1); with the appended STOP that STOP does."""
    size = MEMORY[module]
    p = assemble("#nostop\n" + program(size - 1) + "Last: ROL 0, 1\n", module=module)
    assert len(p.instructions) == size and p.labels["Last"] == size - 1
    p = assemble(program(size - 1), module=module)
    assert len(p.instructions) == size and tuple(p.instructions[-1]) == (28, 0, 0, 0)


@pytest.mark.parametrize("module", sorted(MEMORY))
def test_first_instruction_beyond_memory_is_refused_where_it_stands(module):
    """One instruction more than the memory holds is an error naming that instruction's line (the
    first that does not fit, also when more follow); when it is the appended STOP, the last source
    line is named."""
    size = MEMORY[module]
    e = refused("#nostop\n" + program(size) + "Over: ROL 0, 1\n", module=module)
    assert (e.line, e.column) == (size + 2, 7), str(e)
    assert f"program has {size + 1} instructions; {module} program memory holds {size}" in e.message
    e = refused("#nostop\n" + program(size) + "Over: ROL 0, 1\nROL 0, 2\n", module=module)
    assert (e.line, e.column) == (size + 2, 7), str(e)
    e = refused(program(size), module=module)
    assert (e.line, e.column) == (size, 1), str(e)
    assert f"program has {size + 1} instructions;" in e.message


@pytest.mark.parametrize("module", sorted(MEMORY))
def test_origin_at_the_memory_edge(module):
    """assemble(origin=N) places the program at address N (docs/assumptions.md "Load address"):
    one instruction fits at the last address; the first address beyond it holds none, and from the
    last address a second instruction is refused on its own line."""
    size = MEMORY[module]
    p = assemble("#nostop\nLast: ROL 0, 1\n", module=module, origin=size - 1)
    assert p.labels["Last"] == size - 1 and len(p.instructions) == 1
    e = refused("#nostop\nROL 0, 1\n", module=module, origin=size)
    assert e.line == 2 and f"program has 1 instructions from address {size}" in e.message
    e = refused("#nostop\nROL 0, 1\nROL 0, 2\n", module=module, origin=size - 1)
    assert e.line == 3 and f"from address {size - 1}" in e.message


def test_origin_is_a_program_memory_address():
    """Program memory addresses start at 0 (TMCM-6212 3.6.36, 132 "start address for download"):
    origin 0 is the first, -1 is refused."""
    assert assemble("STOP", origin=0).origin == 0
    with pytest.raises(ValueError, match="origin must be a program memory address >= 0"):
        assemble("STOP", origin=-1)


# --- disassembler: jump targets inside the program ----------------------------------------------

def test_disassembler_labels_targets_up_to_the_end_of_the_program():
    """TMCM-6212 3.6.19 JA "Jump to a fixed address in the TMCL program memory": a target from
    address 0 to the end of the program (one past its last instruction) gets a label; -1 and one
    beyond the end stay numbers."""
    body = [(22, 0, 0, 0), (22, 0, 0, 5), (22, 0, 0, 6), (22, 0, 0, -1), (28, 0, 0, 0)]
    text = disassemble(body + [(28, 0, 0, 0)], comments=False)
    assert [line.strip() for line in text.splitlines()] == [
        "L0:", "JA L0", "JA L5", "JA 6", "JA -1", "STOP", "L5:"]
