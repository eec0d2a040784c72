"""Every error of a source in one run, in source order, each `file:line:column: message`
(docs/tmcl-assembler.md "Errors and warnings"; issue 15 item 6)."""
from __future__ import annotations

import pytest

from opentmcl.lang import AsmError, assemble, assemble_file
from opentmcl.lang.diagnostics import MAX_REPORTED, Diagnostic


def errors_of(source: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as info:
        assemble(source, filename="p.tmc", **kw)
    return info.value


def where(exc: AsmError) -> list[tuple[int, int]]:
    return [(d.line, d.column) for d in exc.errors]


def test_every_error_is_reported_in_source_order():
    """An undefined name on line 1 (found when operands are evaluated) comes before an unknown
    mnemonic on line 2 (found when the line is read): the order is the file's, not the passes'."""
    exc = errors_of("SAP 4, 0, Speed\nFOO 1\nMVP ABS, 0, 1 +\nJA Nowhere\n")
    assert where(exc) == [(1, 11), (2, 1), (3, 16), (4, 4)]
    assert [d.message for d in exc.errors] == ["undefined symbol 'Speed'", "unknown mnemonic 'FOO'",
                                               "expression ends too early", "undefined symbol 'Nowhere'"]
    assert str(exc).splitlines() == ["p.tmc:1:11: undefined symbol 'Speed'", "p.tmc:2:1: unknown mnemonic 'FOO'",
                                     "p.tmc:3:16: expression ends too early", "p.tmc:4:4: undefined symbol 'Nowhere'"]
    assert (exc.file, exc.line, exc.column) == ("p.tmc", 1, 11)  # the first one, as before


def test_the_column_is_the_tokens_and_one_based():
    """Columns count from 1 and point at the operand at fault (tabs count as one column)."""
    exc = errors_of("\tJA   Nowhere\n  MVP ABS, 256, 0\n")
    assert where(exc) == [(1, 7), (2, 12)]
    assert "motor/bank operand must be 0..255, got 256" in exc.errors[1].message


def test_an_include_files_errors_come_where_it_is_included(tmp_path):
    """An error inside an #include'd file is reported at its own file and line, between the
    errors of the lines before and after the #include."""
    (tmp_path / "bad.inc").write_text("OK = 1\nBAD = 1 / 0\nXYZ 1\n")
    main = tmp_path / "main.tmc"
    main.write_text("ROL 0, Nope\n#include bad.inc\nFOO\n")
    with pytest.raises(AsmError) as info:
        assemble_file(main)
    got = [(d.file.rsplit("/", 1)[-1], d.line, d.column) for d in info.value.errors]
    assert got == [("main.tmc", 1, 8), ("bad.inc", 2, 9), ("bad.inc", 3, 1), ("main.tmc", 3, 1)]


def test_a_broken_constant_is_one_error_not_one_per_use():
    """The definition is the error; its uses are not reported again (nor as 'undefined')."""
    exc = errors_of("X = 1 +\nSAP 4, 0, X\nSAP 5, 0, X * 2\nMVP X, 0, 0\n")
    assert where(exc) == [(1, 8)]
    exc = errors_of("Y = 1 / 0\nSAP 4, 0, Y\nSAP 5, 0, Y\n")
    assert where(exc) == [(1, 7)] and exc.errors[0].message == "division by zero"


def test_a_label_defined_twice_and_a_bad_operand_are_both_reported():
    exc = errors_of("L: STOP\nL: STOP\nWAIT POSS, 0, 0\n")
    assert [d.message.split(" ")[0:2] for d in exc.errors] == [["label", "'L'"], ["unknown", "WAIT"]]


@pytest.mark.parametrize("count", [MAX_REPORTED, MAX_REPORTED + 1, 3 * MAX_REPORTED + 7])
def test_at_most_the_limit_is_listed_and_the_rest_is_counted(count):
    """Up to 50 errors are listed (the first ones in the file), the rest are counted: "N more"."""
    exc = errors_of("".join(f"BAD{i} 1\n" for i in range(count)))
    assert len(exc.errors) == MAX_REPORTED
    assert [d.line for d in exc.errors] == list(range(1, MAX_REPORTED + 1))
    assert exc.more == count - MAX_REPORTED
    lines = str(exc).splitlines()
    if count == MAX_REPORTED:
        assert len(lines) == MAX_REPORTED
    else:
        assert len(lines) == MAX_REPORTED + 1
        assert lines[-1].startswith(f"... and {count - MAX_REPORTED} more error")


def test_errors_found_late_still_come_first_in_the_listing():
    """Operand errors are found after every line has been read; they still take their place in
    source order within the 50 listed."""
    source = "SAP 4, 0, Undefined\n" + "".join(f"BAD{i} 1\n" for i in range(2 * MAX_REPORTED))
    exc = errors_of(source)
    assert exc.errors[0].line == 1 and exc.errors[0].message == "undefined symbol 'Undefined'"
    assert exc.more == 2 * MAX_REPORTED + 1 - MAX_REPORTED


def test_a_missing_file_names_no_fake_position(tmp_path):
    """A file that cannot be read has no line or column: `name.tmc: cannot read file: ...`,
    not `name.tmc:0:0` (issue 15 item 5)."""
    path = tmp_path / "missing.tmc"
    with pytest.raises(AsmError) as info:
        assemble_file(path)
    assert str(info.value) == f"{path}: cannot read file: No such file or directory"
    assert ":0:0" not in str(info.value)


def test_warning_format_and_successful_assembly_keeps_them():
    """A warning prints as `file:line:column: warning: message`; a successful assembly returns
    them in `Program.warnings` (in source order) and still produces the program."""
    prog = assemble("SAP 250, 0, 1\nROR 7, 1000\n", filename="w.tmc", module="TMCM-6212")
    assert [str(d) for d in prog.warnings] == [
        "w.tmc:1:5: warning: SAP: TMCM-6212 has no axis parameter 250",
        "w.tmc:2:5: warning: ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)"]
    assert [tuple(i) for i in prog.instructions] == [(5, 250, 0, 1), (1, 0, 7, 1000), (28, 0, 0, 0)]


def test_a_failed_assembly_carries_its_warnings_too():
    exc = errors_of("ROR 7, 1000\nFOO\n", module="TMCM-6212")
    assert [(d.line, d.severity) for d in exc.diagnostics()] == [(1, "warning"), (2, "error")]
    assert [d.line for d in exc.warnings] == [1]


def test_without_a_module_nothing_is_checked():
    """docs/tmcl-assembler.md: without --module no capability is checked."""
    assert assemble("ROR 7, 1000\nSAP 250, 0, 1\n").warnings == []


def test_diagnostic_dictionary_for_the_editor():
    d = Diagnostic("<editor>", 3, 5, "unknown mnemonic 'FOO'")
    assert d.as_dict() == {"file": "<editor>", "line": 3, "column": 5, "severity": "error",
                           "message": "unknown mnemonic 'FOO'"}
