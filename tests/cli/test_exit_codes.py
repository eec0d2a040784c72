"""Issue 15 item 4: the exit statuses of docs/cli.md, through the real CLI (subprocesses).

    0 ok, 1 internal error, 2 usage/bad input, 3 no reply or connection failure,
    4 the module answered with an error status (TMCM-6212 manual 3.2.1: 4 "Invalid value").

The no-reply cases use a real pseudo-terminal nobody answers and a real TCP socket that accepts
and stays silent.
"""
from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading

import pytest

SIM = "sim://TMCM-6212"


def cli(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], capture_output=True, text=True,
                          timeout=timeout)


def one_line(done: subprocess.CompletedProcess[str]) -> str:
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    return lines[0]


def test_2_for_input_that_names_nothing_3_for_a_link_that_fails():
    """Old code: 2 for all of these. A usage mistake or a URL that names no link stays 2; a link
    that names a real place but cannot be opened is 3, and a good request is 0."""
    for argv in (["send"],                                             # argparse: a missing argument
                 ["send", "GAP 1, 0", "--to", SIM, "--bogus"],         # argparse: an unknown option
                 ["send", "GAP 1, 0", "--to", "tcp://"],               # no host and port
                 ["send", "GAP 1, 0", "--to", "nowhere://x"],          # an unknown URL scheme
                 ["send", "GAP 1, 0", "--to", "sim://TMCM-9999"],      # no such module
                 ["send", "SAP 4, 0, 1, 2", "--to", SIM]):             # not an instruction
        done = cli(*argv)
        assert done.returncode == 2 and one_line(done).startswith("opentmcl"), argv
    with socket.socket() as s:   # a port nobody listens on: bound, never listening
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        done = cli("send", "GAP 1, 0", "--to", f"tcp://127.0.0.1:{port}")
    assert done.returncode == 3 and f"tcp://127.0.0.1:{port}" in one_line(done)
    ok = cli("send", "GAP 1, 0", "--to", SIM)
    assert ok.returncode == 0 and ok.stdout == "status 100 (Successfully executed, no error), value 0\n"
    assert ok.stderr == ""


def test_2_for_a_bad_profile_given_to_demo(tmp_path):
    """A profile file the ramp engine refuses is bad input (docs/profiles.md), not a bug: 2."""
    path = tmp_path / "warp.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "W"\n[[axis_parameter]]\nnumber = 4\nengine = "warp"\n')
    done = cli("demo", "--module", str(path), "--duration", "0.1")
    assert done.returncode == 2 and "warp" in one_line(done)


def test_3_no_reply_names_address_and_host_address_on_tcp():
    """A TCP peer that accepts and never answers: the message names what to check."""
    server = socket.create_server(("127.0.0.1", 0))
    held = []
    threading.Thread(target=lambda: held.append(server.accept()), daemon=True).start()
    try:
        done = cli("send", "GAP 1, 0", "--to", f"tcp://127.0.0.1:{server.getsockname()[1]}",
                   "--address", "5", "--host-address", "7", "--timeout", "0.3")
    finally:
        server.close()
        for conn, _ in held:
            conn.close()
    line = one_line(done)
    assert done.returncode == 3 and "no reply from module 5" in line
    assert "module address (5" in line and "GP66" in line and "host address (7" in line and "GP76" in line


@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")
def test_3_no_reply_on_serial_names_the_baud_rate():
    """A real pty nobody answers: the hint adds the baud rate (GP65, "RS485 baud rate", TMCM-6212
    manual 5.1) taken from the URL."""
    master, slave = os.openpty()
    try:
        done = cli("send", "GAP 1, 0", "--to", f"serial://{os.ttyname(slave)}?baud=19200", "--timeout", "0.3")
    finally:
        os.close(master)
        os.close(slave)
    line = one_line(done)
    assert done.returncode == 3 and "no reply from module 1" in line
    assert "baud rate (19200" in line and "GP65" in line and "GP76" in line


def test_4_error_status():
    """SAP 4 (maximum positioning speed) beyond its range: status 4 "Invalid value" (manual 3.2.1)."""
    done = cli("send", "SAP 4, 0, 99999999", "--to", SIM)
    assert done.returncode == 4 and "status 4 (Invalid value)" in one_line(done)


def test_4_for_a_download_the_module_refuses(tmp_path):
    """`load --start` at the first address beyond program memory: the module answers command 132
    with status 4 "Invalid value" (exit 4); the last address is accepted (exit 0)."""
    from opentmcl.lang.binfile import Instruction, encode
    from opentmcl.modules.profile import load_profile

    size = load_profile("TMCM-6212").program_memory
    program = tmp_path / "stop.bin"
    program.write_bytes(encode([Instruction(28, 0, 0, 0)]))   # STOP
    assert cli("load", str(program), "--to", SIM, "--start", str(size - 1)).returncode == 0
    done = cli("load", str(program), "--to", SIM, "--start", str(size))
    assert done.returncode == 4 and "status 4 (Invalid value)" in one_line(done)


_BOOM = """
import sys
from opentmcl.cli import main
from opentmcl.host.connect import register_transport
def factory(url):
    raise RuntimeError("a bug in a transport")
register_transport("boom", factory)
sys.exit(main(sys.argv[1:]))
"""


def test_1_internal_error_is_one_line_asking_for_a_report_and_traceback_only_with_v():
    """An exception nobody expected (a RuntimeError from a transport factory): status 1, one line
    with "please report"; the traceback only with -v."""
    quiet = subprocess.run([sys.executable, "-c", _BOOM, "send", "GAP 1, 0", "--to", "boom://x"],
                           capture_output=True, text=True, timeout=120)
    assert quiet.returncode == 1
    line = one_line(quiet)
    assert "internal error" in line and "RuntimeError: a bug in a transport" in line and "please report" in line
    loud = subprocess.run([sys.executable, "-c", _BOOM, "-v", "send", "GAP 1, 0", "--to", "boom://x"],
                          capture_output=True, text=True, timeout=120)
    assert loud.returncode == 1 and "Traceback (most recent call last)" in loud.stderr
    assert loud.stderr.strip().splitlines()[-1] == line


def test_help_epilog_lists_every_status():
    out = cli("--help").stdout
    block = out[out.index("exit status:"):]
    for code in range(5):
        assert f"\n  {code}  " in block
    assert "please report" in block and "no reply" in block and "error status" in block


@pytest.mark.parametrize("kind", ["missing", "directory"])
def test_2_for_a_profile_check_file_that_cannot_be_read(tmp_path, kind):
    """Issue 15 item 4: "2 usage/bad input ... (and for `replay`-like checks, the code the command
    documents)": `profile check` documents 1 for a file with errors; a FILE that cannot be read at
    all is bad input, 2, with the one-line `opentmcl profile: error:` form, as `replay` does."""
    path = tmp_path / "p.toml"
    if kind == "directory":
        path.mkdir()
    done = cli("profile", "check", str(path))
    assert done.returncode == 2
    assert one_line(done).startswith(f"opentmcl profile: error: cannot read {path}: ")


@pytest.mark.parametrize(("instruction", "url", "status", "fix"), [
    ("SAP 4, 0, 99999999", SIM, "status 4 (Invalid value)",
     "check the value, motor and bank against the module's ranges: see `opentmcl profile show TMCM-6212`"),
    ("SAP 250, 0, 1", "sim://PD86-1180", "status 3 (Wrong type)",
     "the module has no such type or parameter number: see `opentmcl profile show PD86-1180`"),
    ("200, 0, 0, 0", SIM, "status 2 (Invalid command)",
     "the module has no such command: check the command number in its manual"),
])
def test_4_error_status_names_the_likely_fix(instruction, url, status, fix):
    """Issue 15 item 5: "Errors that help: one line, the cause once, and the likely fix". The
    status codes of TMCM-6212 manual 3.2.1 (table 4: 2 Invalid command, 3 Wrong type, 4 Invalid
    value) each end with what to check; the module's ranges are in `opentmcl profile show`."""
    done = cli("send", instruction, "--to", url)
    line = one_line(done)
    assert done.returncode == 4 and status in line and line.endswith(f"at module 1; {fix}"), line
    assert line.count(status) == 1
