"""The assembler's Python API: `assemble()` takes the source text as str or bytes and nothing else;
`assemble_file()` reads the same bytes from a file and passes every option on (defines, origin,
module and strict)."""
from __future__ import annotations

import pytest

from opentmcl.lang.assembler import AsmError, assemble, assemble_file


def test_assemble_refuses_what_is_no_text():
    with pytest.raises(TypeError, match=r"^assemble\(\) takes the source text \(str or bytes\), not int; "
                                        r"assemble_file\(\) reads a file$"):
        assemble(123)  # type: ignore[arg-type]


def test_source_bytes_that_are_no_utf8_are_read_like_a_file():
    """assemble() "takes the source text (str or bytes)" - bytes that are not UTF-8 (a Latin-1
    comment from an old TMCL-IDE file) assemble as assemble_file reads them: each bad byte
    becomes U+FFFD, the instructions are the same."""
    src = b"Start: ROL 0, 500 // Geschwindigkeit f\xfcr Motor 0\nJA Start\n"
    prog = assemble(src)
    assert prog.instructions == [(2, 0, 0, 500), (22, 0, 0, 0), (28, 0, 0, 0)]
    assert "\ufffd" in prog.source[0].text
    assert assemble(bytearray(src)).instructions == prog.instructions


def test_source_bytes_match_assemble_file(tmp_path):
    """The same bytes read from a file (assemble_file) and passed as bytes give the same image."""
    path = tmp_path / "latin1.tmc"
    path.write_bytes(b"// \xe9t\xe9\nMVP ABS, 0, 1000 // \xff\n")
    assert assemble(path.read_bytes()).image() == assemble_file(path).image()


def test_assemble_file_passes_the_defines(tmp_path):
    """`defines` are extra constants (assemble's docstring), for a file as for a text."""
    path = tmp_path / "d.tmc"
    path.write_text("SAP 4, 0, Speed\n")
    assert assemble_file(path, defines={"Speed": 51200}).instructions[0] == (5, 4, 0, 51200)


def test_assemble_file_assembles_for_the_origin(tmp_path):
    """docs/assumptions.md "Load address": "`assemble(..., origin=N)` ... assembles for program
    memory address N: labels are absolute addresses"; assemble_file takes the same `origin`."""
    path = tmp_path / "loop.tmc"
    path.write_text("MST 0\nLoop: ROL 0, 500\nJA Loop\n")
    prog = assemble_file(path, origin=100)
    assert (prog.origin, prog.labels) == (100, {"Loop": 101})
    assert prog.instructions[2] == (22, 0, 0, 101)
    assert assemble_file(path).labels == {"Loop": 1}


def test_assemble_file_with_strict_refuses_what_the_module_cannot_execute(tmp_path):
    """docs/tmcl-assembler.md "Checking against a module": `--strict` makes the warnings errors
    (TMCM-6212 has motors 0..5: ROR 5 is the last valid motor, ROR 6 the first invalid one)."""
    path = tmp_path / "ror.tmc"
    path.write_text("ROR 5, 100\nROR 6, 100\n")
    assert [d.message for d in assemble_file(path, module="TMCM-6212").warnings] == [
        "ROR: motor 6 does not exist on TMCM-6212 (motors 0..5)"]
    with pytest.raises(AsmError) as info:
        assemble_file(path, module="TMCM-6212", strict=True)
    assert (info.value.line, info.value.message) == (2, "ROR: motor 6 does not exist on TMCM-6212 (motors 0..5)")
    path.write_text("ROR 5, 100\n")
    assert assemble_file(path, module="TMCM-6212", strict=True).warnings == []
