"""What `opentmcl send` prints and the hints of its errors, as docs/cli.md shows them (issue 32
items 5 and 6).

Issue 32: "`opentmcl send` prints only the reply value (`0` after `MVP`), so success and a value of
0 look the same. Show the status the way a user reads it. Keep a plain value mode for scripts,
and say in docs/cli.md which is the default"; "The status-4 hint prints a literal `opentmcl
profile show NAME` when the module type is not known; docs/cli.md's no-reply example says
"within 2 s" while `send` waits 5 s". Real parts: CLI processes, a TCP server, a pseudo-terminal.
"""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from opentmcl import VirtualModule
from opentmcl.cli import build_parser, main
from opentmcl.server import Server, TcpServer

ROOT = Path(__file__).resolve().parents[2]
CLI_MD = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "opentmcl", *args], capture_output=True, text=True, timeout=120)


def doc_span(start: str) -> str:
    """The `code span` of docs/cli.md that begins with `start`, its line breaks as blanks."""
    m = re.search(r"`(" + re.escape(start) + r"[^`]*)`", CLI_MD)
    assert m, start
    return " ".join(m.group(1).split())


def test_the_send_example_of_docs_cli_is_what_send_prints():
    """docs/cli.md "What `opentmcl send` prints": the example block, run as it stands."""
    block = CLI_MD.split("## What `opentmcl send` prints", 1)[1].split("```", 2)[1]
    command, *expected = block.strip().splitlines()
    assert command.startswith("$ opentmcl send ")
    done = cli(*shlex.split(command)[2:])
    assert done.returncode == 0 and done.stderr == ""
    assert done.stdout.splitlines() == expected
    assert expected[0] == "status 100 (Successfully executed, no error), value 0"   # MVP: 100 and value 0


def test_the_plain_values_of_docs_cli_are_what_send_plain_prints():
    """The same example with `--plain`: the values the page lists, one a line."""
    block = CLI_MD.split("## What `opentmcl send` prints", 1)[1].split("```", 2)[1]
    command = block.strip().splitlines()[0]
    done = cli(*shlex.split(command)[2:], "--plain")
    assert done.returncode == 0 and done.stdout.splitlines() == ["0", "51200", "6212V105"]
    assert "alone (`0`, `51200`, `6212V105`," in " ".join(CLI_MD.split())


@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")
def test_the_no_reply_example_of_docs_cli_is_sends_own_line_at_its_default_timeout():
    """docs/cli.md's no-reply example names send's default --timeout (5 s, not 2 s) and is, apart
    from that number, the line `send` prints for a serial link nobody answers (a real pty; run
    with --timeout 0.3 to keep the test short)."""
    default = build_parser().parse_args(["send", "GAP 1, 0"]).timeout
    example = doc_span("no reply from module 5")
    assert f" within {default:g} s;" in example and default == 5
    master, slave = os.openpty()
    try:
        done = cli("send", "GAP 1, 0", "--to", f"serial://{os.ttyname(slave)}", "--address", "5", "--timeout", "0.3")
    finally:
        os.close(master)
        os.close(slave)
    assert done.returncode == 3
    assert done.stderr == f"opentmcl send: error: {example.replace(f' within {default:g} s;', ' within 0.3 s;')}\n"


@pytest.fixture
def served(tmp_path):
    """A TCP server of one virtual module, given by name or by a profile file."""
    servers = []

    def serve(module: str) -> str:
        server = Server([VirtualModule(module, address=1)])
        tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0))
        server.start()
        servers.append(server)
        return tcp.url

    yield serve
    for server in servers:
        server.stop()


def status_line(capsys, *argv: str) -> str:
    assert main(["send", *argv]) == 4
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err.strip()


def test_a_status_4_hint_names_the_module_that_answered_over_tcp(capsys, served):
    """Over TCP the command line does not name the module type: `send` asks the module for its
    version string (command 136, TMCM-6212 manual 3.6.36) after the error and names its profile."""
    url = served("PD86-1180")
    line = status_line(capsys, "SAP 4, 0, 99999999", "--to", url)
    assert line.startswith("opentmcl send: error: status 4 (Invalid value) for SAP 4, 0, 99999999 at module 1; ")
    assert line.endswith("check the value, motor and bank against the module's ranges: "
                         "see `opentmcl profile show PD86-1180`")


def test_a_status_3_hint_without_a_known_type_lists_the_choices_not_a_placeholder(capsys, served, tmp_path):
    """A module whose version string names no built-in type (a profile file's "9999V100"): the hint
    says how to find the table instead of printing the placeholder `NAME`."""
    profile = tmp_path / "mine.toml"
    profile.write_text('extends = "TMCM-6212"\n[module]\nname = "MINE-9999"\nfirmware_version = "9999V100"\n')
    url = served(str(profile))
    line = status_line(capsys, "SAP 250, 0, 1", "--to", url)
    assert "status 3 (Wrong type)" in line and "NAME" not in line
    hint = ("see `opentmcl profile show` with the module's type (PD28-1021, PD86-1180, TMCM-6212 or a profile "
            "file; `opentmcl send 136` asks the module)")
    assert line.endswith(f"the module has no such type or parameter number: {hint}")
    assert f"``{hint}``" in " ".join(CLI_MD.split())     # docs/cli.md shows it as it is


def test_a_sim_url_of_one_module_names_it_without_asking(capsys):
    """`sim://TMCM-6212@3` names its module (the address after @ is not part of the name)."""
    line = status_line(capsys, "SAP 4, 0, 99999999", "--to", "sim://TMCM-6212@3", "--address", "3")
    assert line.endswith("see `opentmcl profile show TMCM-6212`")
