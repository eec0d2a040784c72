"""`opentmcl send` against a virtual module."""
from __future__ import annotations

import pytest

from opentmcl.cli import main
from opentmcl.cli.send import parse


def run(capsys, *argv):
    code = main(["send", *argv])
    out, err = capsys.readouterr()
    return code, out.splitlines(), err


def test_parse_uses_the_manuals_mnemonics():
    """TMCM-6212 manual 3.6.4: MVP <ABS|REL|COORD>, <axis>, <position>."""
    assert parse("MVP ABS, 0, 1000") == (4, 0, 0, 1000)
    assert parse("mvp rel, 1, -10000") == (4, 1, 1, -10000)
    assert parse("GAP 1, 0") == (6, 1, 0, 0)
    assert parse("SAP 4, 0, 51200*2") == (5, 4, 0, 102400)
    assert parse("136, 1") == (136, 1, 0, 0)


OK = "status 100 (Successfully executed, no error)"
"""TMCM-6212 manual 3.2.1, table 4: status 100."""


def test_send_shows_each_replys_status_and_value(capsys):
    """Issue 32 item 5: "success and a value of 0 look the same" -- by default each reply shows its
    status in the manual's words (3.2.1, table 4). TMCM-6212 manual 3.6.5/3.6.6: GAP 1 of a fresh
    module is 0; SAP 4, 0, 51200 (its reply value is "don't care"), then GAP 4, 0 reads 51200."""
    code, out, err = run(capsys, "GAP 1, 0", "SAP 4, 0, 51200", "GAP 4, 0", "--to", "sim://TMCM-6212")
    assert code == 0 and err == "" and len(out) == 3
    assert out[0] == f"{OK}, value 0" and out[1].startswith(f"{OK}, value ") and out[2] == f"{OK}, value 51200"


def test_send_plain_prints_the_values_alone_for_scripts(capsys):
    """The plain value mode keeps the old output: one value a line."""
    code, out, err = run(capsys, "GAP 1, 0", "SAP 4, 0, 51200", "GAP 4, 0", "--plain", "--to", "sim://TMCM-6212")
    assert code == 0 and err == "" and len(out) == 3 and out[0] == "0" and out[2] == "51200"


def test_send_in_download_mode_shows_status_101(capsys):
    """TMCM-6212 manual 3.2.1: 101 "Command loaded into TMCL program EEPROM" -- an instruction sent
    after 132 (enter download mode, 3.6.36) is stored, not run: the status tells it apart."""
    code, out, _ = run(capsys, "132, 0, 0, 0", "MVP REL, 0, -10000", "133", "--to", "sim://TMCM-6212")
    assert code == 0 and out[1] == "status 101 (Command loaded into TMCL program EEPROM), value 0"


@pytest.mark.parametrize(("mode", "expected"), [([], "version 1180V445"), (["--plain"], "1180V445"),
                                                (["-v"], "host 2: 1180V445")])
def test_send_version_string(capsys, mode, expected):
    """TMCM-6212 manual 3.6.36: command 136 type 0 returns the version as a string (a special reply
    without a status byte, PD86-1180 manual 4.6.39)."""
    code, out, _ = run(capsys, "136, 0, 0, 0", *mode, "--to", "sim://PD86-1180")
    assert code == 0 and out == [expected]


def test_send_verbose_prints_the_whole_reply(capsys):
    code, out, _ = run(capsys, "GAP 1, 0", "-v", "--to", "sim://TMCM-6212", "--address", "3")
    assert out == ["host 2, module 3, status 100 (Successfully executed, no error), command 6, value 0"]


def test_send_plain_wins_over_verbose_for_the_output(capsys):
    code, out, _ = run(capsys, "GAP 1, 0", "-v", "--plain", "--to", "sim://TMCM-6212")
    assert code == 0 and out == ["0"]


@pytest.mark.parametrize("argv,needle", [
    (["FOO 1, 2", "--to", "sim://TMCM-6212"], "unknown mnemonic"),
    (["MVP ABS, 0", "--to", "sim://TMCM-6212"], "MVP"),
    (["GAP 1, 0", "--to", "nowhere://x"], "unknown URL scheme"),
    (["GAP 1, 0", "--to", "sim://TMCM-6212", "--timeout", "0"], "timeout"),
])
def test_send_errors_are_one_line_with_status_2(capsys, argv, needle):
    """Bad input gives a one-line message, exit status 2, never a traceback (cli/__init__.py)."""
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert needle in err and "Traceback" not in err and len(err.splitlines()) == 1


def test_send_without_url(capsys, monkeypatch):
    monkeypatch.delenv("OPENTMCL_URL", raising=False)
    code, _, err = run(capsys, "GAP 1, 0")
    assert code == 2 and "--to" in err


def test_send_to_a_silent_address_times_out(capsys):
    """No module answers address 9 on this bus: a timeout, reported as an error."""
    code, _, err = run(capsys, "GAP 1, 0", "--to", "sim://TMCM-6212@1", "--address", "9", "--timeout", "0.1")
    assert code == 3 and "no reply from module 9" in err   # 3: no reply (docs/cli.md)


@pytest.mark.parametrize(("mode", "shown"), [([], "instruction MVP REL, 0, -10000"), (["--plain"], "MVP REL, 0, -10000")])
def test_send_read_program_memory_prints_the_instruction(capsys, mode, shown):
    """TMCM-6212 manual 3.6.36: 132 download mode, the instruction is stored (status 101), 133,
    then 134 reads it back."""
    code, out, _ = run(capsys, "132, 0, 0, 0", "MVP REL, 0, -10000", "133", "134, 0, 0, 0", *mode,
                       "--to", "sim://TMCM-6212")
    assert code == 0 and out[-1] == shown
