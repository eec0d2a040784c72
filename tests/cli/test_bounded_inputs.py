"""Issue 11 problem 4: every file the CLI reads is bounded, so an endless input is refused.

Program sizes come from the manuals: TMCM-6212 manual 1, "program memory (non volatile) for up
to 6144 TMCL commands"; PD86-1180 manual: "Program memory (non volatile) for up to 2048 TMCL
commands". The caps (opentmcl.limits, docs/assumptions.md "Bounded inputs") are far above that;
/dev/zero, a FIFO or stdin that never ends must give one error line, exit status 2 (the CLI's code
for bad input, docs), and no output file. Each case is a real `opentmcl` subprocess, run with a
3 GiB address-space limit so a regression fails fast (MemoryError) instead of eating the machine.

Issue 28 item 5 ("a FIFO given as a profile path blocks `open()` for ever"): a path must name a
regular file, so /dev/zero and a FIFO are now refused as such before any byte is read
(tests/cli/test_special_files.py); the caps are met here with regular files of zeros larger than
every cap (sparse, so they take no disk space), and with endless stdin.
"""
import os
import resource
import subprocess
import sys

import pytest

from opentmcl.limits import CSV_MAX, IMAGE_MAX, LINE_MAX, TEXT_MAX

SIM = "sim://TMCM-6212"


def _limit_memory():
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))


def cli(*args, cwd, stdin=subprocess.DEVNULL):
    return subprocess.run([sys.executable, "-m", "opentmcl", *map(str, args)], cwd=cwd, stdin=stdin,
                          capture_output=True, text=True, timeout=120, preexec_fn=_limit_memory)


def refused(res, *words):
    """Exit 2 and exactly one stderr line naming each of `words`, no traceback."""
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2, res.stderr[-500:]
    assert len(lines) == 1 and "Traceback" not in res.stderr, res.stderr[-500:]
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


ENDLESS = 2 * CSV_MAX   # bytes of zeros: larger than every cap of opentmcl.limits


@pytest.fixture
def d(tmp_path):
    for name in ("zero.tmc", "zero.bin", "zero.toml", "zero.yaml", "zero.csv", "zero.txt",
                 "zero.json", "zero.sym", "zero.dbg"):
        with open(tmp_path / name, "wb") as fh:
            fh.truncate(ENDLESS)   # a sparse regular file: zeros, no disk blocks
    (tmp_path / "ok.tmc").write_text("MVP ABS, 0, 1000\nSTOP\n")
    (tmp_path / "ok.bin").write_bytes(bytes([4, 0, 0, 0, 0, 0x03, 0xE8, 0xEF]))
    return tmp_path


def test_asm_of_dev_zero_is_refused_and_writes_nothing(d):
    """Issue 11: "`opentmcl asm /dev/zero -o x.bin` ... grow to gigabytes and never return"; since
    issue 28 the device itself is refused as no regular file."""
    refused(cli("asm", "/dev/zero", "-o", "x.bin", cwd=d), "/dev/zero", "not a regular file")
    refused(cli("asm", "zero.tmc", "-o", "x.bin", cwd=d), "zero.tmc", "4 MiB")
    (d / "big.inc").write_bytes(b"//" + b"x" * TEXT_MAX)   # include files must be regular files
    (d / "inc.tmc").write_text('#include "big.inc"\nSTOP\n')
    refused(cli("asm", "inc.tmc", "-o", "y.bin", "-l", "y.lst", cwd=d), "big.inc", "4 MiB")
    assert not (d / "x.bin").exists() and not (d / "y.bin").exists() and not (d / "y.lst").exists()


def test_disasm_of_endless_file_stdin_and_fifo_is_refused(d):
    """Issue 11: "(and `disasm`)" - a file, stdin '-' and a FIFO (refused as one since issue 28,
    whether a writer is there or not: tests/cli/test_special_files.py)."""
    refused(cli("disasm", "zero.bin", "-o", "x.tmc", cwd=d), "zero.bin", "1 MiB")
    with open("/dev/zero", "rb") as zero:
        refused(cli("disasm", "-", "-o", "y.tmc", cwd=d, stdin=zero), "1 MiB")
    os.mkfifo(d / "pipe.bin")
    refused(cli("disasm", "pipe.bin", "-o", "z.tmc", cwd=d), "pipe.bin", "FIFO")
    refused(cli("disasm", "ok.bin", "-s", "zero.sym", "-o", "w.tmc", cwd=d), "zero.sym", "label table")
    assert not any((d / n).exists() for n in ("x.tmc", "y.tmc", "z.tmc", "w.tmc"))


def test_load_run_debug_refuse_endless_programs_and_command_files(d):
    """The program file of `load`, `run`, `debug` (.tmc and .bin), debug's -x FILE and its stdin."""
    refused(cli("load", "zero.bin", "--to", SIM, cwd=d), "zero.bin", "1 MiB")
    refused(cli("load", "zero.tmc", "--to", SIM, "-m", "TMCM-6212", cwd=d), "zero.tmc", "4 MiB")
    refused(cli("run", "zero.bin", "-t", "0.1", cwd=d), "zero.bin", "1 MiB")
    refused(cli("debug", "zero.tmc", cwd=d), "zero.tmc", "4 MiB")
    refused(cli("debug", "ok.tmc", "-x", "zero.dbg", cwd=d), "zero.dbg", "4 MiB")
    with open("/dev/zero", "rb") as zero:   # commands on stdin that is not a terminal: lines are bounded
        refused(cli("debug", "ok.tmc", cwd=d, stdin=zero), "longer than 4096 characters")


def test_eeprom_and_scenario_files_are_bounded(d):
    """EEPROM images and scenario files (TOML, YAML) of `run`, `demo`, `serve`."""
    refused(cli("run", "ok.tmc", "-t", "0.1", "--eeprom", "zero.json", cwd=d), "zero.json", "4 MiB")
    refused(cli("demo", "--scenario", "zero.toml", cwd=d), "zero.toml", "4 MiB")
    refused(cli("run", "ok.tmc", "-t", "0.1", "--scenario", "zero.yaml", cwd=d), "zero.yaml", "4 MiB")
    refused(cli("serve", "-m", "TMCM-6212", "--eeprom", "zero.json", cwd=d), "zero.json", "4 MiB")


def test_trace_script_and_csv_trace_are_bounded(d):
    """`tmc4210 trace SCRIPT` and the CSV trace of `plot`: no image is written."""
    refused(cli("tmc4210", "trace", "zero.txt", cwd=d), "zero.txt", "4 MiB")
    refused(cli("plot", "zero.csv", "-o", "x.png", cwd=d), "zero.csv", "64 KiB")
    (d / "long.csv").write_text("time_s,position_0\n0," + "1" * LINE_MAX + "\n")
    refused(cli("plot", "long.csv", "-o", "y.png", cwd=d), "long.csv", "line longer")
    assert not (d / "x.png").exists() and not (d / "y.png").exists()


def test_source_cap_edge(tmp_path):
    """Last valid size: a source of exactly TEXT_MAX bytes assembles; one byte more is refused."""
    from opentmcl.lang.assembler import AsmError, assemble_file

    head = b"MVP ABS, 0, 1000\nSTOP\n//"
    src = tmp_path / "edge.tmc"
    src.write_bytes(head + b"x" * (TEXT_MAX - len(head)))
    assert len(assemble_file(src, append_stop=False).instructions) == 2
    src.write_bytes(head + b"x" * (TEXT_MAX - len(head) + 1))
    with pytest.raises(AsmError, match="larger than the 4 MiB limit"):
        assemble_file(src)


def test_image_cap_edge(tmp_path):
    """Last valid size: IMAGE_MAX bytes (131072 records, 21 times the 6144 commands of the
    TMCM-6212) read; the next whole record is refused with BinFileError."""
    from opentmcl.lang import binfile

    record = bytes([4, 0, 0, 0, 0, 0x03, 0xE8, 0xEF])   # MVP ABS, 0, 1000 with its checksum
    img = tmp_path / "edge.bin"
    img.write_bytes(record * (IMAGE_MAX // 8))
    assert len(binfile.read(img)) == IMAGE_MAX // 8
    img.write_bytes(record * (IMAGE_MAX // 8 + 1))
    with pytest.raises(binfile.BinFileError, match="larger than the 1 MiB limit"):
        binfile.read(img)


def test_eeprom_cap_edge(tmp_path):
    """An EEPROM image of exactly TEXT_MAX bytes (JSON padded with spaces) opens; one more byte
    gives EepromError and the file keeps its bytes."""
    from opentmcl.firmware.eeprom import Eeprom, EepromError

    body = b'{"format":"opentmcl-eeprom","version":1,"module":"TMCM-6212","user":{"3":7}}'
    path = tmp_path / "e.json"
    path.write_bytes(body + b" " * (TEXT_MAX - len(body)))
    assert Eeprom(path, "TMCM-6212").get_user(3) == 7
    data = body + b" " * (TEXT_MAX - len(body) + 1)
    path.write_bytes(data)
    with pytest.raises(EepromError, match="larger than the 4 MiB limit"):
        Eeprom(path, "TMCM-6212")
    assert path.read_bytes() == data


def test_csv_line_edge(tmp_path):
    """A CSV line of LINE_MAX characters (newline included) reads; one more character is refused."""
    from opentmcl.trace import Trace, TraceError

    head = "time_s,position_0\n"
    path = tmp_path / "t.csv"
    row = "0," + "0" * (LINE_MAX - 3) + "\n"
    path.write_text(head + row)
    assert Trace.from_csv(path).column(0, "position") == [0.0]
    path.write_text(head + "0," + "0" * (LINE_MAX - 2) + "\n")
    with pytest.raises(TraceError, match="line longer than 64 KiB"):
        Trace.from_csv(path)
