"""Edges of the assembler and disassembler that the lang mutation sample found unpinned
(docs/mutation.md, "lang (sample of 150)"): error positions and messages, the 4 MiB input cap,
the program's file name, and the labels the disassembler chooses."""
from __future__ import annotations

import pytest

from opentmcl.lang import disassemble
from opentmcl.lang.assembler import AsmError, assemble, assemble_file
from opentmcl.limits import TEXT_MAX


def _error(src: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as err:
        assemble(src, **kw)
    return err.value


def test_a_constant_named_like_a_label_is_an_error_at_its_name():
    """docs/tmcl-assembler.md: "each [error] on one line as `file:line:column: message`": the
    column of a constant that repeats a label's name is that of the name."""
    e = _error("Loop: MST 0\n  Loop = 1")
    assert (e.line, e.column, e.message) == (2, 3, "'Loop' is already a label (defined at <source>:1)")


@pytest.mark.parametrize("line", ["#include", '#include ""', "#include <>", "#include // no name"])
def test_include_without_a_file_name(line):
    """docs/assumptions.md (Assembler): "#include accepts `file`, `"file"` or `<file>`" - each
    form without a name is an error naming the expected form."""
    e = _error(line)
    assert (e.line, e.column, e.message) == (1, 1, "expected a file name: #include <file>")


def test_operand_count_errors_use_singular_and_plural():
    """TMCM-6212 3.6.2 "Mnemonic: ROL <axis>, <velocity>", 3.6.21 "Mnemonic: STOP": one operand
    too few or too many is an error at the last operand, "1 operand" / "2 operands"."""
    assert assemble("ROL 0, 51200").instructions[0] == (2, 0, 0, 51200)
    e = _error("ROL 0")
    assert (e.column, e.message) == (5, "ROL does not take 1 operand; expected ROL <motor>, <value>")
    e = _error("STOP 1, 2")
    assert (e.column, e.message) == (9, "STOP does not take 2 operands; expected STOP")


@pytest.mark.parametrize("src", ["X =", "X =   "])
def test_a_constant_without_an_expression(src):
    """7.3 "Using Symbolic Constants" (``Name = value``): no value is an error after the ``=``."""
    e = _error(src)
    assert (e.line, e.column, e.message) == (1, 4, "missing operand")


def test_a_second_definition_is_evaluated_where_it_stands():
    """docs/assumptions.md (Assembler): "a redefinition with the same value is allowed"; an
    undefined name in the second definition is an error on that line, at that name."""
    assert assemble("X = 1\nX = 2 - 1\nSAP 4, 0, X").instructions[0].value == 1
    e = _error("X = 1\nX = Y\nSAP 4, 0, X")
    assert (e.line, e.column, e.message) == (2, 5, "undefined symbol 'Y'")


def test_program_keeps_its_file_name_and_the_listing_shows_bare_line_numbers(tmp_path):
    """Program.filename is the source's name; in the listing its lines show as numbers only,
    an include file's as ``file:line``."""
    (tmp_path / "sub.inc").write_text("MST 1\n")
    path = tmp_path / "main.tmc"
    path.write_text("MST 0\n#include sub.inc\n")
    prog = assemble_file(path)
    assert prog.filename == str(path)
    rows = prog.listing().splitlines()
    assert rows[0] == "0000  03 00 00 00 00 00 00 03       1  MST 0"
    assert rows[1] == f"0001  03 00 01 00 00 00 00 04  {tmp_path / 'sub.inc'}:1  MST 1"
    assert assemble("MST 0").filename == "<source>"
    assert assemble("MST 0").listing().splitlines()[0].endswith("     1  MST 0")


def test_source_file_of_4_mib_is_read_and_one_byte_more_is_refused(tmp_path):
    """docs/tmcl-assembler.md "Input sizes": "a source file (and each include file) may have at most
    4 MiB": exactly TEXT_MAX bytes assemble; one more is an error with no position (line 0)."""
    assert TEXT_MAX == 4 * 1024 * 1024
    ok, big = tmp_path / "ok.tmc", tmp_path / "big.tmc"
    ok.write_text("// " + "x" * (TEXT_MAX - 4) + "\n")
    big.write_text("// " + "x" * (TEXT_MAX - 3) + "\n")
    assert ok.stat().st_size == TEXT_MAX and big.stat().st_size == TEXT_MAX + 1
    assert assemble_file(ok).instructions == [(28, 0, 0, 0)]
    with pytest.raises(AsmError) as err:
        assemble_file(big)
    e = err.value
    assert (e.file, e.line, e.column) == (str(big), 0, 0)
    assert e.message == "program source is larger than the 4 MiB limit"


def test_include_file_over_4_mib_is_an_error_at_the_include(tmp_path):
    """The same cap for each include file: the error is at the #include line and gives the reason."""
    (tmp_path / "big.inc").write_text("// " + "x" * (TEXT_MAX - 3) + "\n")
    e = _error("MST 0\n#include big.inc", filename=str(tmp_path / "main.tmc"))
    assert (e.line, e.column) == (2, 1)
    assert e.message == f"cannot read include file {tmp_path / 'big.inc'}: program source is larger than the 4 MiB limit"


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


# --- the second half of the sample (--sample 300) ---------------------------------------------

def test_raw_with_too_few_operands_is_an_error_at_the_last_one():
    """docs/tmcl-assembler.md: "`RAW command, type, motor, value` emits any record verbatim":
    four operands; fewer is an error at the last operand given, at the mnemonic when none is."""
    assert assemble("RAW 136, 1, 0, 0").instructions[0] == (136, 1, 0, 0)
    for src, col in (("RAW", 1), ("  RAW", 3), ("RAW 1, 2, 3", 11)):
        e = _error(src)
        assert (e.column, e.message) == (col, "expected RAW <command>, <type>, <motor>, <value>")


@pytest.mark.parametrize(("src", "col", "usage"), [
    ("MVP ABS, , 1", 10, "MVP ABS|REL|COORD, <motor>, <value>"),
    ("RAW 1, , 0, 0", 8, "RAW <command>, <type>, <motor>, <value>"),
])
def test_an_empty_operand_names_the_usage(src, col, usage):
    """Operands are separated by commas (docs/tmcl-assembler.md "Source format"); nothing between
    two commas is an error at the second one's operand, with the command's operand forms."""
    e = _error(src)
    assert (e.column, e.message) == (col, f"empty operand; expected {usage}")


def test_a_redefinition_names_the_line_of_the_first_definition():
    """docs/assumptions.md (Assembler): "a different value is an error": at the second definition,
    naming where the first one is."""
    e = _error("X = 1\n\nX = 2\nMST X")
    assert (e.line, e.column, e.message) == (3, 1, "constant 'X' redefined as 2 (was 1 at <source>:1)")


def test_assemble_file_passes_the_defines(tmp_path):
    """`defines` are extra constants (assemble's docstring), for a file as for a text."""
    path = tmp_path / "d.tmc"
    path.write_text("SAP 4, 0, Speed\n")
    assert assemble_file(path, defines={"Speed": 51200}).instructions[0] == (5, 4, 0, 51200)


@pytest.mark.parametrize("origin", [0, 1, 5])
def test_listing_shows_a_label_after_the_last_instruction(origin):
    """A label after the last instruction (the end of a `#nostop` program) is the address after it
    and ends the listing, at any load address."""
    prog = assemble("#nostop\nMST 0\nEnd:", origin=origin)
    assert prog.labels == {"End": origin + 1}
    assert prog.listing().splitlines()[-1].strip() == "End:"


def test_a_profile_file_that_cannot_be_used_has_no_position(tmp_path):
    """docs/assumptions.md (Assembler, Diagnostics): "A diagnostic without a position (unreadable
    file, bad `--module`) prints `file: message`" - line and column 0."""
    bad = tmp_path / "bad.toml"
    bad.write_text("not toml [[[\n")
    e = _error("MST 0", module=str(bad))
    assert (e.file, e.line, e.column) == (str(bad), 0, 0)
    assert e.message.startswith(f"cannot use the module profile: {bad}: not TOML")
    assert str(e).startswith(f"{bad}: cannot use the module profile")


def test_global_parameter_access_in_the_warning():
    """TMCM-6212 5.1 (Bank 0): GP128 "TMCL application status ... R" cannot be written (SGP), GP132 "TMCL
    tick timer ... RW" can, but has no E, so STGP cannot store it (Table 15, the access letters)."""
    warnings = assemble("SGP 128, 0, 1\nSGP 132, 0, 1\nSTGP 132, 0", module="TMCM-6212").warnings
    assert [(w.line, w.message) for w in warnings] == [
        (1, "SGP: global parameter 128 (tmcl_application_status) of TMCM-6212 cannot be written"),
        (3, "STGP: global parameter 132 (tick_timer) of TMCM-6212 cannot be stored to or restored from EEPROM"),
    ]


# --- names the previous round listed (not in this draw; docs/mutation.md) ---------------------

def test_defines_are_constants_from_the_options():
    """`defines` are extra constants (`asm -D NAME=VALUE`): one the source defines again with
    another value, or uses as a label, is an error that names `<defines>` (no line: 0)."""
    assert assemble("X = 1\nMST X", defines={"X": 1}).instructions[0] == (3, 0, 1, 0)
    e = _error("X = 2\nMST X", defines={"X": 1})
    assert (e.line, e.column, e.message) == (1, 1, "constant 'X' redefined as 2 (was 1 at <defines>:0)")
    e = _error("X: MST 0", defines={"X": 1})
    assert e.message == "'X' is already a constant (defined at <defines>:0)"


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


def test_binfile_checksum_error_names_the_byte_offset():
    """docs/tmcl-assembler.md "Binary file format": 8-byte records; a wrong checksum names the
    record and its byte offset (8 x record) with both checksums in hex."""
    from opentmcl.lang import binfile
    data = bytearray(binfile.encode([binfile.Instruction(3), binfile.Instruction(28)]))
    data[15] ^= 1
    with pytest.raises(binfile.BinFileError) as err:
        binfile.decode(bytes(data))
    assert str(err.value) == "record 1 (byte offset 8): wrong checksum 1Dh, expected 1Ch"


def test_binfile_read_takes_1_mib_and_refuses_one_byte_more(tmp_path):
    """docs/tmcl-assembler.md "Input sizes": "a binary image ... at most 1 MiB = 131072 records";
    an all-zero record is a valid one (checksum 0)."""
    from opentmcl.lang import binfile
    from opentmcl.limits import IMAGE_MAX
    assert IMAGE_MAX == 131072 * 8
    ok, big = tmp_path / "ok.bin", tmp_path / "big.bin"
    ok.write_bytes(bytes(IMAGE_MAX))
    big.write_bytes(bytes(IMAGE_MAX + 1))
    assert len(binfile.read(ok)) == 131072
    with pytest.raises(binfile.BinFileError) as err:
        binfile.read(big)
    assert str(err.value) == "binary program image is larger than the 1 MiB limit"


# --- a further draw of 450 (docs/mutation.md) --------------------------------------------------

@pytest.mark.parametrize(("expr", "value"), [("-7 % 3", -1), ("7 % -3", 1), ("7 % 3", 1),
                                             ("-7 / 2", -3), ("7 / -2", -3), ("-7 / -2", 3)])
def test_division_and_remainder_follow_c(expr, value):
    """docs/assumptions.md (Assembler): "C integer semantics (`/` truncates toward zero, `%` takes
    the dividend's sign)"."""
    assert assemble(f"SAP 4, 0, {expr}").instructions[0].value == value


def test_nostop_takes_no_argument():
    """`#nostop` (docs/tmcl-assembler.md): alone it drops the STOP; with an argument it is an error."""
    assert assemble("MST 0\n#nostop // a comment").instructions == [(3, 0, 0, 0)]
    e = _error("#nostop 1")
    assert (e.line, e.column, e.message) == (1, 1, "#nostop takes no argument")


def test_unknown_module_is_an_error_of_the_options():
    """A module name that is no profile: one error of `<options>` without a position; nothing more
    is counted (AsmError.more, warnings_more 0)."""
    e = _error("MST 0", module="TMCM-9999")
    assert (e.file, e.line, e.column) == ("<options>", 0, 0)
    assert e.message.startswith("unknown module 'TMCM-9999'; known: PD28-1021, PD86-1180, TMCM-6212")
    assert (e.more, e.warnings_more, len(e.errors), e.warnings) == (0, 0, 1, [])


def test_assemble_refuses_what_is_no_text():
    with pytest.raises(TypeError, match=r"^assemble\(\) takes the source text \(str or bytes\), not int; "
                                        r"assemble_file\(\) reads a file$"):
        assemble(123)  # type: ignore[arg-type]


def test_binfile_of_a_partial_record_names_the_record():
    """8-byte records: 9 bytes are record 0 and one byte of record 1; 16 bytes are two records."""
    from opentmcl.lang import binfile
    assert len(binfile.decode(bytes(16))) == 2
    with pytest.raises(binfile.BinFileError) as err:
        binfile.decode(bytes(9))
    assert str(err.value) == "length 9 is not a multiple of 8 bytes (record 1 is incomplete)"
