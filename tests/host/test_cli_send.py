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


def test_send_prints_each_replys_value(capsys):
    """TMCM-6212 manual 3.6.5/3.6.6: SAP 4, 0, 51200 then GAP 4, 0 reads 51200 back."""
    code, out, err = run(capsys, "SAP 4, 0, 51200", "GAP 4, 0", "--to", "sim://TMCM-6212")
    assert code == 0 and len(out) == 2 and out[1] == "51200" and err == ""  # SAP value: don't care


def test_send_version_string(capsys):
    """TMCM-6212 manual 3.6.36: command 136 type 0 returns the version as a string."""
    code, out, _ = run(capsys, "136, 0, 0, 0", "--to", "sim://PD86-1180")
    assert code == 0 and out == ["1180V445"]


def test_send_verbose_prints_the_whole_reply(capsys):
    code, out, _ = run(capsys, "GAP 1, 0", "-v", "--to", "sim://TMCM-6212", "--address", "3")
    assert out == ["host 2, module 3, status 100 (Successfully executed, no error), command 6, value 0"]


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


def test_send_read_program_memory_prints_the_instruction(capsys):
    """TMCM-6212 manual 3.6.36: 132 download mode, the instruction is stored (status 101), 133,
    then 134 reads it back."""
    code, out, _ = run(capsys, "132, 0, 0, 0", "MVP REL, 0, -10000", "133", "134, 0, 0, 0",
                       "--to", "sim://TMCM-6212")
    assert code == 0 and out[-1] == "MVP REL, 0, -10000"
