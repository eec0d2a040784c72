"""ASCII interface codec (PD28-1021 manual 3.4, PD86-1180 manual 4.5)."""
from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.protocol import ascii
from opentmcl.protocol.ascii import AsciiCommand, AsciiError, EchoMode
from opentmcl.protocol.frame import Request
from opentmcl.protocol.status import Status


@pytest.mark.parametrize(("line", "expected"), [
    ("AMVP ABS, 1, 50000", AsciiCommand(1, "MVP", 4, 0, 1, 50000)),
    ("A MVP ABS, 1, 50000", AsciiCommand(1, "MVP", 4, 0, 1, 50000)),
    ("AROL 2, 500", AsciiCommand(1, "ROL", 2, 0, 2, 500)),
    ("A MST 1", AsciiCommand(1, "MST", 3, 0, 1, 0)),
    ("ABIN", AsciiCommand(1, "BIN", None)),
])
def test_manual_command_lines(line, expected):
    """PD28-1021 3.4.2 "Here are some examples for valid ASCII mode command lines (assuming that the
    module address is 1)", with and without the terminating <CR>."""
    assert ascii.parse_command(line) == expected
    assert ascii.parse_command(line + "\r") == expected


def test_address_character():
    """3.4.2: "A when the module address is 1, B for modules with address 2 and so on"; to address
    module 3 use C (PD86-1180 4.5.1)."""
    assert ascii.parse_command("CGAP 1, 0").address == 3
    assert ascii.address_letter(1) == "A" and ascii.address_letter(3) == "C"
    assert ascii.letter_address("B") == 2
    with pytest.raises(AsciiError):
        ascii.address_letter(27)
    with pytest.raises(AsciiError):
        ascii.parse_command("1MVP ABS, 1, 5")


def test_command_line_to_binary_request():
    """The ASCII line carries the same command as the binary form (3.4: "entered as in the TMCL-IDE")."""
    assert ascii.parse_command("AGAP 0, 1").to_request() == Request(1, 6, 0, 1, 0)
    assert ascii.parse_command("ARFS STATUS, 0").to_request() == Request(1, 13, 2, 0, 0)
    with pytest.raises(AsciiError, match="BIN"):
        ascii.parse_command("ABIN").to_request()


def test_reply_line():
    """PD28-1021 3.4.3: "after sending AGAP 0, 1 the reply would be BA 100 -5000 if the actual
    position of axis 1 is -5000, the host address is set to 2 and the module address is 1"."""
    assert ascii.format_reply(2, 1, 100, -5000) == "BA 100 -5000"
    assert ascii.encode_reply(2, 1, 100, -5000) == b"BA 100 -5000\r"
    assert ascii.parse_reply("BA 100 -5000\r") == ascii.AsciiReply(2, 1, 100, -5000)


def test_reply_line_with_the_1180_manuals_dash():
    """PD86-1180 4.5.2 prints the reply as "BA 100 \u20135000" (typographic dash)."""
    assert ascii.parse_reply("BA 100 \u20135000").value == -5000


def test_only_listed_commands_are_accepted():
    """3.4: "Only the following commands can be used in ASCII mode: ROL, ROR, MST, MVP, SAP, GAP,
    STAP, RSAP, SGP, GGP, STGP, RSGP, RFS, SIO, GIO, SCO, GCO, CCO, UF0..UF7"."""
    with pytest.raises(AsciiError, match="cannot be used in ASCII mode") as exc:
        ascii.parse_command("AJA 10")
    assert exc.value.status == Status.INVALID_COMMAND
    assert ascii.parse_command("AUF3 1, 2, 3") == AsciiCommand(1, "UF3", 67, 1, 2, 3)


def test_special_commands():
    """3.4: BIN quits ASCII mode; RUN starts the TMCL program; STOP stops it (control commands
    129 and 128, not opcode 28)."""
    assert ascii.parse_command("ARUN").to_request() == Request(1, 129, 0, 0, 0)
    assert ascii.parse_command("ARUN 10").to_request() == Request(1, 129, 1, 0, 10)
    assert ascii.parse_command("ASTOP").to_request() == Request(1, 128, 0, 0, 0)
    assert ascii.parse_command("ABIN").is_bin
    assert ascii.ENTER_COMMAND == 139


@pytest.mark.parametrize(("line", "status"), [
    ("", Status.INVALID_COMMAND),
    ("A", Status.INVALID_COMMAND),
    ("AFOO 1", Status.INVALID_COMMAND),
    ("AMVP ABS, 1", Status.WRONG_TYPE),
    ("AMVP XYZ, 1, 5", Status.WRONG_TYPE),
    ("AMVP ABS, X, 5", Status.INVALID_VALUE),
    ("ASAP 300, 0, 1", Status.WRONG_TYPE),
    ("AMVP ABS, 1, 99999999999", Status.INVALID_VALUE),
    ("AMVP,1", Status.INVALID_COMMAND),
])
def test_malformed_lines(line, status):
    with pytest.raises(AsciiError) as exc:
        ascii.parse_command(line)
    assert exc.value.status == status


def test_echo_configuration():
    """3.4.4: global parameter 67 bit 0 = start in ASCII mode; bits 4/5 choose the echo."""
    assert ascii.starts_in_ascii(1) and not ascii.starts_in_ascii(0)
    assert ascii.echo_mode(0) is EchoMode.CHARACTER
    assert ascii.echo_mode(0x10) is EchoMode.LINE
    assert ascii.echo_mode(0x20) is EchoMode.NONE


def test_format_command():
    assert ascii.format_command(1, "mvp", "ABS", 1, 50000) == "AMVP ABS, 1, 50000"
    assert ascii.format_command(2, "BIN") == "BBIN"


@given(st.text(max_size=40))
def test_any_line_parses_or_raises_ascii_error(line):
    """Bad input from a terminal is a typed AsciiError with a TMCL status, never another exception."""
    for text in (line, "A" + line, "AMVP " + line):
        try:
            cmd = ascii.parse_command(text)
        except AsciiError as exc:
            assert exc.status in (Status.INVALID_COMMAND, Status.WRONG_TYPE, Status.INVALID_VALUE)
        else:
            assert 1 <= cmd.address <= 26
        try:
            ascii.parse_reply(text)
        except AsciiError:
            pass
