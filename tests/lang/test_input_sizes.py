"""docs/tmcl-assembler.md "Input sizes": a source file and each include file hold at most 4 MiB, a
binary program image at most 1 MiB - the largest input is read, one byte more is a clear error."""
from __future__ import annotations

import pytest

from opentmcl.lang.assembler import AsmError, assemble, assemble_file
from opentmcl.limits import TEXT_MAX


def _error(src: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as err:
        assemble(src, **kw)
    return err.value


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
