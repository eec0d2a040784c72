"""Range edges of the assembler: the last valid value and the first invalid one of each limit
(docs/tmcl-assembler.md "Values are signed 32 bit ...; type and motor/bank are 0..255", the
program memory of the module, the nesting limits; docs/assumptions.md "nesting limit 32")."""
from __future__ import annotations

import pytest

from opentmcl.lang.assembler import MAX_EXPR_DEPTH, MAX_INCLUDE_DEPTH, AsmError, assemble
from opentmcl.modules.profile import load_profile


def _error(src: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as err:
        assemble(src, **kw)
    return err.value


@pytest.mark.parametrize("name", ["TMCM-6212", "PD86-1180"])
def test_a_program_that_fills_the_memory_exactly_assembles(name):
    """1 Features: the program memory holds `program_memory` commands (6144 / 2048). size - 1
    instructions and the appended STOP fill it exactly; one more is an error naming the size."""
    size = load_profile(name).program_memory
    assert len(assemble("MST 0\n" * (size - 1), module=name).instructions) == size
    with pytest.raises(AsmError, match=rf"program has {size + 1} instructions; {name} program memory holds {size}"):
        assemble("MST 0\n" * size, module=name)


def test_the_origin_may_be_the_last_address():
    """`origin` (the load address): one instruction at the last address fits, at the size it does not."""
    size = load_profile("PD86-1180").program_memory
    prog = assemble("STOP", module="PD86-1180", append_stop=False, origin=size - 1)
    assert prog.instructions == [(28, 0, 0, 0)]
    with pytest.raises(AsmError, match=rf"from address {size}; PD86-1180 program memory holds {size}"):
        assemble("STOP", module="PD86-1180", append_stop=False, origin=size)


def test_a_program_too_large_from_an_origin_is_reported_at_the_first_instruction_past_the_end():
    """TMCM-6212 manual 1 Features: "program memory (non volatile) for up to 6144 TMCL commands";
    docs/assumptions.md "Load address": with origin N "the size check counts from N". Loaded at
    6144 - 6, six instructions and the STOP fill the memory exactly; at 6144 - 4 the fifth
    instruction is the first one at address 6144, beyond the memory, and the error is on its line
    (docs/tmcl-assembler.md: "the column is that of the token at fault")."""
    size = load_profile("TMCM-6212").program_memory
    assert size == 6144
    src = "".join(f"MST {i}\n" for i in range(6))          # lines 1..6, then the appended STOP
    fits = assemble(src, module="TMCM-6212", origin=size - 7)
    assert len(fits.instructions) == 7 and fits.origin + len(fits.instructions) == size
    origin = size - 4                                    # addresses size-4 .. size+2
    e = _error(src, module="TMCM-6212", origin=origin)
    first_outside = size - origin + 1                    # line of the instruction at address `size`
    assert (e.line, e.column) == (first_outside, 1) == (5, 1)
    assert e.message == f"program has 7 instructions from address {origin}; TMCM-6212 program memory holds {size}"


def test_a_program_without_instructions_beyond_the_memory_is_an_error_without_a_position():
    """The same rule when the source has no instruction to point at (only comments and constants,
    or nothing): the appended STOP at the size is an error naming the file, line 0 (docs/
    tmcl-assembler.md: line 0 is "no position"); at the last address it fits."""
    size = load_profile("TMCM-6212").program_memory
    assert assemble("", module="TMCM-6212", origin=size - 1).instructions == [(28, 0, 0, 0)]
    for source, append_stop in (("", True), ("// a comment\nK = 1\n", True), ("", False)):
        with pytest.raises(AsmError) as err:
            assemble(source, filename="empty.tmc", module="TMCM-6212", origin=size + 1 - append_stop,
                     append_stop=append_stop)
        count = int(append_stop)
        assert str(err.value) == (f"empty.tmc: program has {count} instructions from address {size + 1 - append_stop}; "
                                  f"TMCM-6212 program memory holds {size}")
        assert (err.value.line, err.value.column) == (0, 0)


def test_type_and_motor_take_255_and_refuse_256():
    """Type and motor/bank are one byte each: 0 and 255 are accepted, -1 and 256 refused."""
    assert assemble("SAP 255, 255, 1").instructions[0] == (5, 255, 255, 1)
    assert assemble("SAP 0, 0, 1").instructions[0] == (5, 0, 0, 1)
    for src, what in (("SAP 256, 0, 1", "type operand must be 0..255, got 256"),
                      ("SAP -1, 0, 1", "type operand must be 0..255, got -1"),
                      ("SAP 4, 256, 1", "motor/bank operand must be 0..255, got 256")):
        with pytest.raises(AsmError, match=what):
            assemble(src)


@pytest.mark.parametrize("value", ["-2147483649", "0x100000000", "4294967296"])
def test_values_one_beyond_32_bit_are_errors(value):
    """"Values are signed 32 bit (`0xFFFFFFFF` is -1)": -2147483648 and 0xFFFFFFFF are the ends
    (tests/lang/test_assembler.py); one beyond either end is an error."""
    with pytest.raises(AsmError, match="value operand out of 32-bit range"):
        assemble(f"SAP 4, 0, {value}")


def test_unary_signs_up_to_the_nesting_limit():
    """"at most 100 levels of parentheses and unary signs": 99 signs in front of a number
    assemble, 101 are an error at the column of the sign that is one too many."""
    assert MAX_EXPR_DEPTH == 100
    assert assemble("SAP 4, 0, " + "-" * 99 + "1").instructions[0].value == -1
    assert assemble("SAP 4, 0, " + "(" * 99 + "7" + ")" * 99).instructions[0].value == 7
    with pytest.raises(AsmError, match="nested deeper than 100 levels") as err:
        assemble("SAP 4, 0, " + "-" * 101 + "1")
    assert err.value.column == len("SAP 4, 0, ") + 101


def test_includes_nest_32_deep_and_not_33(tmp_path):
    """docs/assumptions.md (Assembler): "nesting limit 32": a chain of 32 include files assembles,
    33 is an error that names the file whose #include is one too deep."""
    assert MAX_INCLUDE_DEPTH == 32

    def chain(n: int) -> str:
        for i in range(n):
            (tmp_path / f"i{i}.inc").write_text(f"#include i{i + 1}.inc\n" if i + 1 < n else "X = 7\n")
        return str(tmp_path / "main.tmc")

    src = "#include i0.inc\nSAP 4, 0, X"
    assert assemble(src, filename=chain(32)).instructions[0] == (5, 4, 0, 7)
    with pytest.raises(AsmError, match="includes nested deeper than 32") as err:
        assemble(src, filename=chain(33))
    assert err.value.file.endswith("i31.inc")


@pytest.mark.parametrize("form", ["Interrupts.inc", '"Interrupts.inc"', "<Interrupts.inc>"])
def test_include_accepts_the_three_spellings(form):
    """docs/assumptions.md (Assembler): "#include accepts `file`, `"file"` or `<file>`": each form
    finds the bundled Interrupts.inc (TI_GLOBAL = 255, TMCM-6212 Table 12)."""
    assert assemble(f"#include {form}\nEI TI_GLOBAL").instructions[0] == (25, 255, 0, 0)


def test_an_expression_that_stops_after_an_operator_names_the_problem():
    """Errors name line, column and cause (docs/tmcl-assembler.md): an operand ending in an
    operator is "expression ends too early"."""
    with pytest.raises(AsmError, match="expression ends too early"):
        assemble("SAP 4, 0, 1 +")


def test_an_unreadable_file_is_an_error_at_line_0_column_0(tmp_path):
    """assemble_file: "AsmError (line 0) if it cannot be read" - no line, no column."""
    from opentmcl.lang.assembler import assemble_file

    with pytest.raises(AsmError, match="cannot read file") as err:
        assemble_file(tmp_path / "missing.tmc")
    assert (err.value.line, err.value.column) == (0, 0)
