"""Issue 15 item 3: -v/--verbose (repeatable: -v INFO, -vv DEBUG) and -q/--quiet, before the command
or after it (docs/cli.md "Logging"), through the real CLI.

Vector: MVP ABS, 0, 51200 (TMCM-6212 manual 3.6.3) is the frame 01 04 00 00 00 00 c8 00 cd
(module address 1, command 4, type 0, motor 0, value 51200, checksum: manual 3.2).
"""
from __future__ import annotations

import subprocess
import sys

import pytest

from opentmcl.protocol.frame import Request

SIM = "sim://TMCM-6212"
SENT = "DEBUG opentmcl.host.transport: -> MVP ABS, 0, 51200  [" + Request(1, 4, 0, 0, 51200).encode().hex(" ") + "]"


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("argv", [
    ["-vv", "send", "MVP ABS, 0, 51200", "--to", SIM],
    ["send", "MVP ABS, 0, 51200", "--to", SIM, "-vv"],
    ["--verbose", "--verbose", "send", "MVP ABS, 0, 51200", "--to", SIM],
])
def test_vv_logs_every_frame_as_tmcl_text_and_hex(argv):
    done = cli(*argv)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert SENT in lines
    assert any(line.startswith("DEBUG opentmcl.host.transport: <- MVP reply from 1 to 2: status 100") for line in lines)


def test_default_logs_nothing_and_v_only_info():
    quiet = cli("send", "MVP ABS, 0, 51200", "--to", SIM)
    assert quiet.returncode == 0 and quiet.stderr == ""
    info = cli("-v", "load", "--help")   # argparse help: no command runs, nothing logged
    assert info.returncode == 0 and info.stderr == ""
    one = cli("-v", "profile", "probe", "sim://PD28-1021", "--max-seconds", "60")
    assert one.returncode == 0
    assert "DEBUG" not in one.stderr


def test_v_and_q_on_every_subcommand_and_nested_ones():
    """`profile probe -q` (a nested subcommand), `tmc4210 convert --verbose` (its -v is --velocity)."""
    assert cli("profile", "probe", "sim://PD28-1021", "-q").stderr == ""
    assert "probe: axis 0:" in cli("profile", "probe", "sim://PD28-1021").stderr
    done = cli("tmc4210", "convert", "-v", "100", "-p", "3", "--verbose")
    assert done.returncode == 0, done.stderr
    for command in ("demo", "asm", "disasm", "serve", "dashboard", "replay", "log", "debug", "run"):
        text = cli(command, "--help").stdout
        assert "-v, --verbose" in text and "-q, --quiet" in text, command
