"""`opentmcl asm` and `opentmcl disasm`."""
from __future__ import annotations

from pathlib import Path

from opentmcl.cli import main

from ..capture.helpers import cli

EXAMPLES = Path(__file__).parent / "examples"


def test_asm_then_disasm_round_trip(tmp_path, capsys):
    """The TMCM-6212 2.4 program: asm writes the .bin, disasm prints source that assembles to it."""
    out = tmp_path / "p.bin"
    assert main(["asm", str(EXAMPLES / "tmcm6212_2_4_simple.tmc"), "-o", str(out), "-m", "TMCM-6212"]) == 0
    data = out.read_bytes()
    assert len(data) == 14 * 8 and data[-8:] == bytes.fromhex("1C0000000000001C")
    capsys.readouterr()
    assert main(["disasm", str(out)]) == 0
    text = capsys.readouterr().out
    src = tmp_path / "back.tmc"
    src.write_text(text)
    out2 = tmp_path / "q.bin"
    assert main(["asm", str(src), "-o", str(out2)]) == 0
    assert out2.read_bytes() == data


def test_asm_counts_what_disasm_lists(tmp_path):
    """Issue 29 item 9: `asm` said "14 instructions" where `disasm` shows 13. It counts the source's
    instructions apart from the STOP it appends (docs/tmcl-assembler.md), in the singular for one,
    and without the appended STOP it says why `disasm` lists one fewer for a final STOP."""
    src, out = tmp_path / "p.tmc", tmp_path / "p.bin"
    src.write_text("    MVP ABS, 0, 500\n    STOP\n")
    r = cli("asm", str(src), "-o", str(out))
    assert r.stdout.strip() == f"{out}: 2 instructions + appended STOP = 3 records, 0 labels"
    assert len(cli("disasm", str(out)).stdout.splitlines()) == 2
    r = cli("asm", str(src), "-o", str(out), "--no-stop")
    assert r.stdout.strip() == f"{out}: 2 instructions (disasm lists 1: it leaves a final STOP out), 0 labels"
    assert len(cli("disasm", str(out)).stdout.splitlines()) == 1
    src.write_text("Here:\n    MVP ABS, 0, 500\n")
    r = cli("asm", str(src), "-o", str(out))
    assert r.stdout.strip() == f"{out}: 1 instruction + appended STOP = 2 records, 1 label"


def test_asm_listing_and_symbols_to_stdout(tmp_path, capsys):
    src = tmp_path / "a.tmc"
    src.write_text("Loop: ROL 0, 500\nJA Loop\n")
    assert main(["asm", str(src), "-s", "-"]) == 0
    assert capsys.readouterr().out == "Loop\t0\n"
    assert (tmp_path / "a.bin").is_file()  # default output name
    assert main(["asm", str(src), "-l", "-", "-D", "X=1"]) == 0
    assert "0001  16 00 00 00 00 00 00 16" in capsys.readouterr().out


def test_asm_error_is_one_line_exit_2(tmp_path, capsys):
    """Errors: one line naming file, line and column; exit status 2; no traceback."""
    src = tmp_path / "bad.tmc"
    src.write_text("ROL 0, 1\nWAIT POSS, 0, 0\n")
    assert main(["asm", str(src)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{src}:2:6: unknown WAIT type 'POSS'" in err
    assert "Traceback" not in err
    assert not (tmp_path / "bad.bin").exists()


def test_asm_missing_file_and_bad_define(tmp_path, capsys):
    assert main(["asm", str(tmp_path / "none.tmc")]) == 2
    assert "cannot read file" in capsys.readouterr().err
    src = tmp_path / "a.tmc"
    src.write_text("STOP\n")
    assert main(["asm", str(src), "-D", "X"]) == 2
    assert "NAME=NUMBER" in capsys.readouterr().err


def test_disasm_errors(tmp_path, capsys):
    bad = tmp_path / "bad.bin"
    bad.write_bytes(b"\x01\x02\x03")
    assert main(["disasm", str(bad)]) == 2
    assert "multiple of 8" in capsys.readouterr().err
    assert main(["disasm", str(tmp_path / "none.bin")]) == 2
    assert "cannot read" in capsys.readouterr().err


def test_disasm_with_symbol_file(tmp_path, capsys):
    src = tmp_path / "a.tmc"
    src.write_text("Start: ROL 0, 500\nJA Start\n")
    assert main(["asm", str(src), "-s", str(tmp_path / "a.sym")]) == 0
    capsys.readouterr()
    assert main(["disasm", str(tmp_path / "a.bin"), "-s", str(tmp_path / "a.sym"), "--no-comments"]) == 0
    assert capsys.readouterr().out == "Start:\n    ROL 0, 500\n    JA Start\n"
