"""Special files given as input paths (issue 28 item 5: "a FIFO given as a profile path blocks
`open()` for ever").

Every path OpenTMCL reads must name a regular file (docs/assumptions.md "Special files"): a FIFO,
a device or a directory is refused at once, with one line naming the path and what it is, exit
status 2 (bad input, docs/cli.md), and nothing written. The FIFOs here have no writer, so an
`open()` that waits for one never returns: each command runs as a real `opentmcl` subprocess with
a time-out far above its normal run time, and a hang fails the test. Stdin ('-') may be a pipe.
"""
from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest

from opentmcl.limits import NotRegularFile, open_regular, read_bytes

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX FIFOs")

HANG = 60   # seconds: every command below ends in about one second


@pytest.fixture
def d(tmp_path):
    for name in ("p.toml", "p.tmc", "p.bin", "p.jsonl", "p.json", "p.csv", "p.txt", "p.dbg", "p.sym", "p.yaml"):
        os.mkfifo(tmp_path / name)
    (tmp_path / "ok.tmc").write_text("MVP ABS, 0, 1000\nSTOP\n")
    (tmp_path / "ok.bin").write_bytes(bytes([4, 0, 0, 0, 0, 0x03, 0xE8, 0xEF]))
    return tmp_path


def cli(*args: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], cwd=cwd, stdin=subprocess.DEVNULL,
                          capture_output=True, text=True, timeout=HANG)


def test_open_regular_refuses_a_fifo_a_device_and_a_directory_at_once(tmp_path):
    """A FIFO without a writer: plain open() would wait for one; open_regular returns at once with
    NotRegularFile (an OSError) saying what the path is. /dev/null is a character device; a
    directory is IsADirectoryError. A regular file, also behind a symbolic link, opens."""
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    started = time.monotonic()
    with pytest.raises(NotRegularFile) as err:
        open_regular(fifo)
    assert time.monotonic() - started < HANG
    assert err.value.strerror == "a FIFO (named pipe), not a regular file" and err.value.filename == str(fifo)
    with pytest.raises(NotRegularFile, match="a character device, not a regular file"):
        read_bytes("/dev/null", 10)
    with pytest.raises(IsADirectoryError):
        read_bytes(tmp_path, 10)
    (tmp_path / "f.txt").write_bytes(b"abc")
    (tmp_path / "link.txt").symlink_to(tmp_path / "f.txt")
    assert read_bytes(tmp_path / "link.txt", 3) == b"abc"
    with open_regular(tmp_path / "f.txt") as fh:
        assert fh.read() == b"abc"


CASES = [
    (["profile", "check", "p.toml"], "p.toml"),
    (["profile", "show", "p.toml"], "p.toml"),
    (["serve", "--module", "p.toml", "--tcp", "127.0.0.1:0"], "p.toml"),
    (["send", "--to", "sim:///{d}/p.toml", "GAP 1, 0"], "p.toml"),
    (["run", "ok.tmc", "-t", "0.1", "--module", "p.toml"], "p.toml"),
    (["asm", "p.tmc", "-o", "x.bin"], "p.tmc"),
    (["asm", "ok.tmc", "--module", "p.toml", "-o", "x.bin"], "p.toml"),
    (["disasm", "p.bin", "-o", "x.tmc"], "p.bin"),
    (["disasm", "ok.bin", "-s", "p.sym", "-o", "x.tmc"], "p.sym"),
    (["load", "p.bin", "--to", "sim://TMCM-6212"], "p.bin"),
    (["load", "p.tmc", "--to", "sim://TMCM-6212", "-m", "TMCM-6212"], "p.tmc"),
    (["run", "p.bin", "-t", "0.1"], "p.bin"),
    (["debug", "p.tmc"], "p.tmc"),
    (["debug", "ok.tmc", "-x", "p.dbg"], "p.dbg"),
    (["run", "ok.tmc", "-t", "0.1", "--eeprom", "p.json"], "p.json"),
    (["serve", "-m", "TMCM-6212", "--eeprom", "p.json", "--tcp", "127.0.0.1:0"], "p.json"),
    (["run", "ok.tmc", "-t", "0.1", "--scenario", "p.toml"], "p.toml"),
    (["demo", "--scenario", "p.yaml", "--duration", "0.1"], "p.yaml"),
    (["replay", "p.jsonl"], "p.jsonl"),
    (["log", "show", "p.jsonl"], "p.jsonl"),
    (["plot", "p.csv", "-o", "x.png"], "p.csv"),
    (["tmc4210", "trace", "p.txt"], "p.txt"),
]


@pytest.mark.parametrize(("argv", "name"), CASES, ids=[" ".join(c[0][:2]) + " " + c[1] for c in CASES])
def test_every_input_path_refuses_a_fifo_with_one_line(d, argv, name):
    """Profiles, programs (.tmc, .bin), label tables, debugger command files, EEPROM images,
    scenarios, captures, CSV traces and TMC4210 scripts: one line naming the FIFO, exit 2, no
    output file."""
    done = cli(*[a.replace("{d}", str(d).lstrip("/")) for a in argv], cwd=d)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2, done.stderr[-500:]
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr[-500:]
    assert name in lines[0] and "FIFO" in lines[0], lines[0]
    assert not any((d / out).exists() for out in ("x.bin", "x.tmc", "x.png"))


def test_dev_zero_is_refused_as_a_device(tmp_path):
    """/dev/zero as a profile or a capture: a character device, refused before a byte is read."""
    for argv in (["profile", "check", "/dev/zero"], ["serve", "--module", "/dev/zero", "--tcp", "127.0.0.1:0"],
                 ["log", "show", "/dev/zero"]):
        done = cli(*argv, cwd=tmp_path)
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1, done.stderr[-500:]
        assert "/dev/zero" in lines[0] and "character device" in lines[0], lines[0]


def test_stdin_may_still_be_a_pipe(tmp_path):
    """'-' is stdin, which may be a pipe (`disasm -`): only paths must name regular files."""
    done = subprocess.run([sys.executable, "-m", "opentmcl", "disasm", "-"], cwd=tmp_path,
                          input=bytes([4, 0, 0, 0, 0, 0x03, 0xE8, 0xEF]), capture_output=True, timeout=HANG)
    assert done.returncode == 0, done.stderr
    assert b"MVP ABS, 0, 1000" in done.stdout
