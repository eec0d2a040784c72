"""Assembler syntax and error reporting."""
from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.lang.assembler import AsmError, assemble, assemble_file

STOP = (28, 0, 0, 0)


def ins(src: str, **kw) -> list[tuple[int, int, int, int]]:
    return [tuple(i) for i in assemble(src, **kw).instructions]


def err(src: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as exc:
        assemble(src, filename="t.tmc", **kw)
    return exc.value


def _error(src: str, **kw) -> AsmError:
    """As `err`, with the default file name `<source>`."""
    with pytest.raises(AsmError) as info:
        assemble(src, **kw)
    return info.value


def test_trailing_stop_is_appended():
    """docs/tmcl-assembler.md (TMCL-IDE .bin): a STOP follows the last source instruction - even an explicit one."""
    assert ins("ROL 0, 1") == [(2, 0, 0, 1), STOP]
    assert ins("STOP") == [STOP, STOP]
    assert ins("") == [STOP]
    assert ins("#nostop\nROL 0, 1") == [(2, 0, 0, 1)]
    assert ins("ROL 0, 1", append_stop=False) == [(2, 0, 0, 1)]


def test_nostop_takes_no_argument():
    """`#nostop` (docs/tmcl-assembler.md): alone it drops the STOP; with an argument it is an error."""
    assert assemble("MST 0\n#nostop // a comment").instructions == [(3, 0, 0, 0)]
    e = _error("#nostop 1")
    assert (e.line, e.column, e.message) == (1, 1, "#nostop takes no argument")


def test_case_insensitive_mnemonics_and_symbols():
    """Mnemonics and symbolic operands in any case (manual 3.6: "MVP ABS, 0, 90000")."""
    assert ins("mvp abs, 0, 90000\nMvP Rel, 0, -5\nwait ticks, 0, 5")[:3] == [
        (4, 0, 0, 90000), (4, 1, 0, -5), (27, 0, 0, 5)]


def test_literals():
    """Decimal, negative, 0x and $ hex, 0b binary; values wrap to signed 32 bit."""
    assert ins("SAP 4, 0, 0x10\nSAP 4, 0, $FF\nSAP 4, 0, 0b101\nSAP 4, 0, -2147483648\nSAP 4, 0, 0xFFFFFFFF")[:5] == [
        (5, 4, 0, 16), (5, 4, 0, 255), (5, 4, 0, 5), (5, 4, 0, -2147483648), (5, 4, 0, -1)]


def test_constants_and_expressions():
    """Constants (manual 7.3), forward references, C-like integer arithmetic."""
    src = "Speed = Base * 2 + 1\nBase = 100\nSAP 4, 0, Speed\nSAP 5, 0, (Base - 7) / 2\nSAP 6, 0, -7 / 2\n" \
          "SAP 7, 0, -7 % 2\nSAP 8, 0, 1 << 4 | 3\nSAP 9, 0, ~0"
    assert ins(src)[:6] == [(5, 4, 0, 201), (5, 5, 0, 46), (5, 6, 0, -3), (5, 7, 0, -1), (5, 8, 0, 19),
                            (5, 9, 0, -1)]


def test_labels_forms():
    """Labels alone, before an instruction, with space before ':', several on one line, at the end."""
    p = assemble("A:\nB : C: ROL 0, 1\nJA A\nJA End\nEnd:")
    assert p.labels == {"A": 0, "B": 0, "C": 0, "End": 3}
    assert [tuple(i) for i in p.instructions][1:3] == [(22, 0, 0, 0), (22, 0, 0, 3)]


def test_labels_usable_in_any_value():
    """A label is a number: e.g. the start address given to a user variable."""
    assert ins("SGP 0, 2, Here\nHere: STOP")[0] == (9, 0, 2, 1)


def test_optional_forms():
    """GAP with a third (don't care) operand (PD86-1180 4.6.18), RFS START without motor
    (TMCM-6212 3.6.11 caption), CALC NOT without operand."""
    assert ins("GAP 1, 0, 0\nRFS START\nCALC NOT")[:3] == [(6, 1, 0, 0), (13, 0, 0, 0), (19, 8, 0, 0)]


def test_extended_commands():
    """PD28-1021 3.5 Table 5: the extended commands and their operand forms."""
    src = ("CALCVV ADD, 1, 2\nCALCVA SUB, 3\nCALCAV MUL, 4\nCALCVX DIV, 5\nCALCXV SWAP, 6\nCALCV ADD, 7, 100\n"
           "MVPA REL, 0\nRST 0\nDJNZ 9, Top\nTop: ROLA 0\nRORA 0\nSIV 42\nGIV\nAIV\nCALL EQ, Top\nUF3 1, 2, 3")
    assert ins(src, module="PD28-1021")[:16] == [
        (40, 0, 1, 2), (41, 1, 3, 0), (42, 2, 4, 0), (43, 3, 5, 0), (44, 10, 6, 0), (45, 0, 7, 100),
        (46, 1, 0, 0), (48, 0, 0, 0), (49, 9, 0, 9), (50, 0, 0, 0), (51, 0, 0, 0), (55, 0, 0, 42),
        (56, 0, 0, 0), (57, 0, 0, 0), (80, 2, 0, 9), (67, 1, 2, 3)]


def test_raw_pseudo_instruction():
    """Our RAW pseudo-instruction (docs/assumptions.md) emits any record, e.g. control command 136."""
    assert ins("RAW 136, 1, 0, -5") == [(136, 1, 0, -5), STOP]


def test_error_names_file_line_column_and_expected_form():
    e = err("ROL 0, 1\n  MVP ABS, 0\n")
    assert (e.file, e.line, e.column) == ("t.tmc", 2, 12)
    assert "expected MVP ABS|REL|COORD, <motor>, <value>" in e.message
    assert str(e).startswith("t.tmc:2:12: ")


@pytest.mark.parametrize(("src", "line", "column", "text"), [
    ("FOO 1", 1, 1, "unknown mnemonic 'FOO'"),
    ("WAIT POSS, 0, 0", 1, 6, "unknown WAIT type 'POSS'; expected TICKS|POS|REFSW|LIMSW|RFS"),
    ("JA Nowhere", 1, 4, "undefined symbol 'Nowhere'"),
    ("Loop: STOP\nJA loop", 2, 4, "did you mean 'Loop'"),
    ("SAP 256, 0, 1", 1, 5, "type operand must be 0..255"),
    ("SAP 4, -1, 1", 1, 8, "motor/bank operand must be 0..255"),
    ("SAP 4, 0, 4294967296", 1, 11, "out of 32-bit range"),
    ("SAP 4, 0, 1/0", 1, 12, "division by zero"),
    ("SAP 4, 0, (1", 1, 13, "missing ')'"),
    ("SAP 4, 0, 1 2", 1, 13, "unexpected '2'"),
    ("SAP 4, , 1", 1, 8, "empty operand"),
    ("SAP 4, 0, #", 1, 11, "unexpected character '#'"),
    ("A: STOP\nA: STOP", 2, 1, "label 'A' already defined at t.tmc:1"),
    ("X = 1\nX = 2\nSTOP", 2, 1, "redefined as 2"),
    ("X = Y\nY = X\nSAP 4, 0, X", 2, 5, "constant defined in terms of itself"),
    ("X = 1\nX: STOP", 2, 1, "already a constant"),
    ("#include nothere.inc", 1, 1, "include file 'nothere.inc' not found"),
    ("#pragma once", 1, 1, "unknown directive '#pragma'"),
    ("RAW 1, 2", 1, 8, "expected RAW <command>, <type>, <motor>, <value>"),
    ("  ,", 1, 3, "expected a label, a constant definition or an instruction"),
])
def test_errors(src, line, column, text):
    """Every error names file, line and 1-based column of the offending token and what was expected."""
    e = err(src)
    assert (e.line, e.column) == (line, column), str(e)
    assert text in e.message


def test_operand_count_errors_use_singular_and_plural():
    """TMCM-6212 3.6.2 "Mnemonic: ROL <axis>, <velocity>", 3.6.21 "Mnemonic: STOP": one operand
    too few or too many is an error at the last operand, "1 operand" / "2 operands"."""
    assert assemble("ROL 0, 51200").instructions[0] == (2, 0, 0, 51200)
    e = _error("ROL 0")
    assert (e.column, e.message) == (5, "ROL does not take 1 operand; expected ROL <motor>, <value>")
    e = _error("STOP 1, 2")
    assert (e.column, e.message) == (9, "STOP does not take 2 operands; expected STOP")


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


def test_duplicate_identical_constant_is_allowed():
    """Include files may define the same name twice with the same value."""
    assert assemble("X = 1\nX = 1\nSAP 4, 0, X").constants == {"X": 1}


def test_module_checks_commands_and_memory():
    """With a module: commands it lacks are warnings, errors with strict (issue 15 item 6; STAP is
    in the PD86-1180 set, the extended set only in the PD28-1021's), and a program larger than its
    memory is an error."""
    assert ins("STAP 4, 0", module="PD86-1180")[0] == (7, 4, 0, 0)
    e = err("ROL 0, 1\nCALCVV ADD, 1, 2", module="PD86-1180", strict=True)
    assert (e.line, e.column) == (2, 1) and "not available on PD86-1180" in e.message
    w = assemble("ROL 0, 1\nCALCVV ADD, 1, 2", module="PD86-1180").warnings
    assert [(d.line, d.column, d.severity) for d in w] == [(2, 1, "warning")]
    assert ins("CALCVV ADD, 1, 2")[0] == (40, 0, 1, 2)  # no module: no check
    from opentmcl.modules.profile import load_profile
    size = load_profile("PD86-1180").program_memory
    with pytest.raises(AsmError, match="program memory holds"):
        assemble("ROL 0, 1\n" * size, module="PD86-1180")


def test_unknown_module():
    """Module names are those of the profiles (TMCM-6212, PD86-1180, PD28-1021 and aliases)."""
    with pytest.raises(AsmError, match="unknown module"):
        assemble("STOP", module="TMCM-9999")


def test_unknown_module_is_an_error_of_the_options():
    """A module name that is no profile: one error of `<options>` without a position; nothing more
    is counted (AsmError.more, warnings_more 0)."""
    e = _error("MST 0", module="TMCM-9999")
    assert (e.file, e.line, e.column) == ("<options>", 0, 0)
    assert e.message.startswith("unknown module 'TMCM-9999'; known: PD28-1021, PD86-1180, TMCM-6212")
    assert (e.more, e.warnings_more, len(e.errors), e.warnings) == (0, 0, 1, [])


def test_includes_search_path_and_once(tmp_path):
    """#include searches the including file's directory, then the include path; a file is read once."""
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "speeds.inc").write_text("Fast = 1000 // from lib\n#include other.inc\n")
    (tmp_path / "other.inc").write_text("Slow = 10\n")
    (tmp_path / "main.tmc").write_text('#include "speeds.inc"\n#include speeds.inc\nROL 0, Fast\nROR 0, Slow\n')
    p = assemble_file(tmp_path / "main.tmc", include_path=[tmp_path / "lib", tmp_path])
    assert [tuple(i) for i in p.instructions] == [(2, 0, 0, 1000), (1, 0, 0, 10), STOP]
    (tmp_path / "bad.inc").write_text("ROL 0,\n")
    (tmp_path / "m2.tmc").write_text("STOP\n#include bad.inc\n")
    with pytest.raises(AsmError) as exc:
        assemble_file(tmp_path / "m2.tmc")
    assert exc.value.file.endswith("bad.inc") and exc.value.line == 1


def test_unreadable_source(tmp_path):
    """A missing source file is an AsmError (line 0), not an OSError traceback."""
    with pytest.raises(AsmError, match="cannot read file"):
        assemble_file(tmp_path / "missing.tmc")


def test_defines():
    """Constants given from outside (CLI -D NAME=VALUE) behave like `Name = value` (manual 7.3)."""
    assert ins("ROL 0, Speed", defines={"Speed": 7})[0] == (2, 0, 0, 7)


def test_listing_and_symbol_file():
    """Listing: address, the 8 record bytes, source line and text; symbol file: label and address
    (what TMCM-6212 7.6 calls the symbol file, used to find run addresses)."""
    p = assemble("Loop: ROL 0, 1 // go\nJA Loop", filename="x.tmc")
    lines = p.listing().splitlines()
    assert lines[0].strip() == "Loop:"
    assert lines[1].startswith("0000  02 00 00 00 00 00 01 03") and lines[1].endswith("1  Loop: ROL 0, 1 // go")
    assert lines[3].startswith("0002  1C 00 00 00 00 00 00 1C") and "appended" in lines[3]
    assert p.symbol_file() == "Loop\t0\n"


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


@pytest.mark.parametrize("origin", [0, 1, 5])
def test_listing_shows_a_label_after_the_last_instruction(origin):
    """A label after the last instruction (the end of a `#nostop` program) is the address after it
    and ends the listing, at any load address."""
    prog = assemble("#nostop\nMST 0\nEnd:", origin=origin)
    assert prog.labels == {"End": origin + 1}
    assert prog.listing().splitlines()[-1].strip() == "End:"


@pytest.mark.parametrize(("src", "text"), [
    ("SAP 4, 0, " + "(" * 300 + "1" + ")" * 300, "nested deeper"),
    ("SAP 4, 0, " + "-" * 300 + "1", "nested deeper"),
    ("C0 = 0xFFFFFFFF\n" + "".join(f"C{i} = C{i - 1} * C{i - 1}\n" for i in range(1, 40)) + "SAP 4, 0, C39",
     "more than 64 bits"),
    ("SAP 4, 0, 1 << 64", "out of range"),
])
def test_hostile_expressions_are_errors_not_crashes(src, text):
    """Bad input gives a typed error, never a crash or a hang (house rules)."""
    with pytest.raises(AsmError, match=text):
        assemble(src)


def test_bom_and_crlf():
    """Files saved by Windows editors (BOM, CR LF line ends) assemble like plain ones."""
    assert ins("\ufeffROL 0, 1\r\nMST 0\r\n") == [(2, 0, 0, 1), (3, 0, 0, 0), STOP]

_SOURCE_ALPHABET = st.sampled_from(list("ABCDEFGHIJKLMNOPQRSTUVWXYZabcxyz0123456789_,:=+-*/%&|^~()<>$#\"' \t\n")
                                   + ["MVP ", "ABS", "JA ", "WAIT ", "TICKS", "//", "#include ", "0x", "\x00",
                                      "\u00e9", "\u0663", "RAW ", "#nostop", "Loop:", "\r\n"])


@given(st.lists(_SOURCE_ALPHABET, max_size=60).map("".join))
def test_any_text_assembles_or_raises_asm_error(src):
    """Bad input: a typed AsmError with a position, never another exception (house rules)."""
    try:
        prog = assemble(src, filename="fuzz.tmc")
    except AsmError as exc:
        assert exc.file == "fuzz.tmc" or exc.file.startswith("<bundled>") or exc.line == 0
        assert exc.line >= 0 and exc.column >= 0
    else:
        assert len(prog.image()) % 8 == 0
