"""Edges of the ASCII command line and of the instruction parser that the full mutation run of
the protocol layer found unpinned (docs/mutation.md): the ASCII-only commands, the operand
ranges of type and motor/bank, symbols only in the type field, and the refusal messages."""
from __future__ import annotations

import pytest

from opentmcl.protocol import ascii
from opentmcl.protocol.ascii import AsciiError
from opentmcl.protocol.frame import FrameError, Request
from opentmcl.protocol.opcodes import OperandError, parse_instruction
from opentmcl.protocol.replies import MemoryReply
from opentmcl.protocol.status import Status


@pytest.mark.parametrize("mnemonic", ["BIN", "STOP"])
def test_bin_and_stop_take_no_operands(mnemonic):
    """PD28-1021 3.4: "BIN: This command quits ASCII mode and returns to binary mode." and "STOP:
    Stops a TMCL program": neither has an operand; one is refused, naming the command."""
    with pytest.raises(AsciiError, match=rf"^{mnemonic} takes no operands$"):
        ascii.parse_command(f"A{mnemonic} 1")


def test_run_with_and_without_start_address():
    """PD28-1021 3.4: "RUN: This command can be used to start a TMCL program stored in memory":
    without an operand it is command 129 type 0, with a start address 129 type 1 (docs/assumptions.md);
    the parsed command keeps the mnemonic RUN in both forms."""
    plain = ascii.parse_command("ARUN")
    assert (plain.mnemonic, plain.to_request()) == ("RUN", Request(1, 129, 0, 0, 0))
    start = ascii.parse_command("BRUN 17")
    assert (start.mnemonic, start.to_request()) == ("RUN", Request(2, 129, 1, 0, 17))


def test_run_refusals_name_the_problem():
    """A start address that is no number is status 4 and named "address"; a second operand is
    refused with a message that says RUN takes one at most."""
    with pytest.raises(AsciiError, match=r"^address must be a number, got 'x'$") as err:
        ascii.parse_command("ARUN x")
    assert err.value.status == Status.INVALID_VALUE
    with pytest.raises(AsciiError, match=r"^RUN takes at most one operand \(start address\)$"):
        ascii.parse_command("ARUN 1, 2")


def test_type_and_motor_take_0_to_255():
    """TMCM-6212 3.1: type and motor/bank are one byte each: 255 is the last value of both; 256 is
    "3 Wrong type" in the type field and "4 Invalid value" in the motor/bank field (3.2.1), and
    the message names the field and the command."""
    assert ascii.parse_command("ASAP 255, 255, 0").to_request() == Request(1, 5, 255, 255, 0)
    with pytest.raises(AsciiError, match=r"^type of SAP must be 0..255, got 256$") as err:
        ascii.parse_command("ASAP 256, 0, 0")
    assert err.value.status == Status.WRONG_TYPE
    with pytest.raises(AsciiError, match=r"^motor of ROL must be 0..255, got 256$") as err:
        ascii.parse_command("AROL 256, 500")
    assert err.value.status == Status.INVALID_VALUE


def test_symbols_name_only_the_type_field():
    """TMCM-6212 3.6.4 "MVP <ABS|REL|COORD>, <motor>, <position|offset>": ABS/REL/COORD are type
    names; in the motor or value field they are no number (status 4 in ASCII mode)."""
    assert ascii.parse_command("AMVP REL, 0, 1").to_request() == Request(1, 4, 1, 0, 1)
    with pytest.raises(AsciiError, match=r"^motor must be a number, got 'ABS'$") as err:
        ascii.parse_command("AMVP ABS, ABS, 0")
    assert err.value.status == Status.INVALID_VALUE
    with pytest.raises(OperandError, match=r"^'MVP ABS, 0, REL': cannot read value operand 'REL'$"):
        parse_instruction("MVP ABS, 0, REL")


def test_unknown_type_names_the_accepted_forms():
    """An unknown type word is "3 Wrong type"; the message quotes the word and the usage."""
    with pytest.raises(AsciiError, match=r"^unknown type 'FOO' for MVP; expected MVP ABS\|REL\|COORD, "
                                         r"<motor>, <value>$") as err:
        ascii.parse_command("AMVP FOO, 0, 0")
    assert err.value.status == Status.WRONG_TYPE


def test_overlong_type_literal_names_the_type():
    """A type literal longer than the literal limit is status 4, and the message names the type."""
    with pytest.raises(AsciiError, match=r"^type: ") as err:
        ascii.parse_command("ASAP " + "1" * 5000 + ", 0, 0")
    assert err.value.status == Status.INVALID_VALUE


def test_memory_reply_decodes_without_checksum_check_when_asked():
    """TMCM-6212 3.6.36: 134 has a "special reply format"; read with `verify=False` a frame whose
    checksum byte is wrong still gives its fields (docs/assumptions.md), by default it is refused."""
    good = MemoryReply(2, 4, 0, 1, 1000).encode()
    bad = good[:8] + bytes([good[8] ^ 0xFF])
    assert MemoryReply.decode(bad, verify=False) == MemoryReply(2, 4, 0, 1, 1000)
    with pytest.raises(FrameError, match=r"^wrong checksum$"):
        MemoryReply.decode(bad)


def test_wrong_operand_count_names_every_accepted_form():
    """TMCM-6212 3.6.34 gives UF0..UF7 three, two, one or no operands; five is none of them:
    "3 Wrong type" (docs/assumptions.md, ASCII interface), and the message lists the forms."""
    with pytest.raises(AsciiError, match=r"^wrong operands for UF0; expected UF0 <type>, <motor>, <value> or "
                                         r"UF0 <type>, <motor> or UF0 <type> or UF0$") as err:
        ascii.parse_command("AUF0 1, 2, 3, 4, 5")
    assert err.value.status == Status.WRONG_TYPE


def test_fields_left_out_are_zero():
    """PD28-1021 3.4.2 sends "the command with its parameters"; a field the short form leaves out
    (the motor of "RFS START", every field of "UF3") is 0 in the binary request."""
    assert ascii.parse_command("ARFS START").to_request() == Request(1, 13, 0, 0, 0)
    assert ascii.parse_command("AUF3").to_request() == Request(1, 67, 0, 0, 0)


def test_line_edges_empty_blank_and_trailing_letters():
    """PD28-1021 3.4.2: "At the end of a command line a <CR> character has to be sent": only the
    <CR> (or LF) is cut off, so a last letter is still part of the value and an address character
    followed by blanks has no command. A line with nothing before <CR> is empty."""
    with pytest.raises(AsciiError, match=r"^empty command line$"):
        ascii.parse_command("\r")
    with pytest.raises(AsciiError, match=r"^missing command after address character in 'A '$"):
        ascii.parse_command("A \r")
    with pytest.raises(AsciiError, match=r"^value must be a number, got 'X'$"):
        ascii.parse_command("ASAP 4, 0, X\r")


def test_blanks_before_the_address_character_are_skipped():
    """PD28-1021 3.4.2: "As the first character, the address character has to be sent"; blanks a
    terminal sends before it are skipped (docs/mutation.md names this reading)."""
    assert ascii.parse_command("  BMST 0\r").to_request() == Request(2, 3, 0, 0, 0)


@pytest.mark.parametrize("dash", ["\u2013", "\u2212", "-"])
def test_reply_value_with_the_manuals_dashes(dash):
    """PD86-1180 4.5.2: "the reply would be BA 100 \u20135000 if the actual position of axis 1 is
    \u20135000": the en dash (and the minus sign of 4.6.4, "\u22122.147.483.648") read as '-', also
    with a blank between sign and digits."""
    assert ascii.parse_reply(f"BA 100 {dash}5000\r") == ascii.AsciiReply(2, 1, 100, -5000)
    assert ascii.parse_reply(f"BA 100 {dash} 5000") == ascii.AsciiReply(2, 1, 100, -5000)


def test_reply_refusals():
    """A reply line is two address characters, the status and the value as decimal numbers
    (PD28-1021 3.4.3): a letter after the value, or a status literal beyond the 32-digit limit, is
    no reply line; a signed status of exactly 32 digits still is one."""
    with pytest.raises(AsciiError, match=r"^not an ASCII reply line: 'BA 100 5X'$"):
        ascii.parse_reply("BA 100 5X")
    assert ascii.parse_reply("BA +" + "1" * 32 + " 0").status == int("1" * 32)
    with pytest.raises(AsciiError, match=r"^not an ASCII reply line: number literal of 33 digits is too long"):
        ascii.parse_reply("BA " + "1" * 33 + " 0")


def test_can_request_byte_refusal_names_the_motor():
    """TMCM-6212 3.1: the motor/bank field is one byte; 256 is refused, naming the field."""
    from opentmcl.protocol import can

    assert can.encode_request(6, 1, 255, 0)[2] == 255
    with pytest.raises(can.CanFrameError, match=r"^motor must be 0..255, got 256$"):
        can.encode_request(6, 1, 256, 0)


def test_usage_of_label_commands():
    """TMCM-6212 3.6.16 "Mnemonic: JC <condition>, <label>", 3.6.17 "Mnemonic: JA <label>": the value
    of a jump is a label; the operand of 3.6.15 COMP stays "<value>"."""
    from opentmcl.protocol.opcodes import by_mnemonic

    assert by_mnemonic("JA").usage() == "JA <label>"
    assert by_mnemonic("JC").usage() == "JC ZE|NZ|EQ|NE|GT|GE|LT|LE|ETO|EAL|EDV|EPO|ESD, <label>"
    assert by_mnemonic("COMP").usage() == "COMP <value>"


@pytest.mark.parametrize("dash", ["\u2212", "\u2013"])
def test_number_literals_with_the_manuals_minus(dash):
    """PD86-1180 4.6.4: "The range of the MVP command is 32 bit signed (\u22122.147.483.648\u2026
    +2.147.483.647)": the manual's minus sign and en dash are read as '-' in a literal."""
    from opentmcl.protocol.opcodes import parse_number

    assert parse_number(f"{dash}2147483648") == -2**31
    assert parse_instruction(f"MVP ABS, 0, {dash}5") == (4, 0, 0, -5)


@pytest.mark.parametrize("letter", ["1", "\u00c4", "AB", ""])
def test_address_character_is_one_letter_a_to_z(letter):
    """PD28-1021 3.4.2: "The address character is A when the module address is 1, B for modules
    with address 2 and so on": a digit, a letter outside A..Z or two letters are refused, quoted."""
    with pytest.raises(AsciiError, match=rf"^address character must be a letter A..Z, got {letter!r}$"):
        ascii.letter_address(letter)
    assert ascii.letter_address("z") == 26


def test_reply_and_frame_decoding_defaults():
    """TMCM-6212 3.2: a reply is nine bytes ending in a checksum; decoding checks the checksum
    unless told not to, and a wrong length is named with what was decoded ("reply", "frame")."""
    from opentmcl.protocol.frame import Reply, decode_frame

    good = Reply(2, 1, 100, 6, -5000).encode()
    bad = good[:8] + bytes([good[8] ^ 0xFF])
    assert Reply.decode(bad, verify=False) == Reply(2, 1, 100, 6, -5000)
    with pytest.raises(FrameError, match=r"^wrong checksum$"):
        Reply.decode(bad)
    with pytest.raises(FrameError, match=r"^reply must be 9 bytes, got 8$"):
        Reply.decode(good[:8])
    with pytest.raises(FrameError, match=r"^wrong checksum$"):
        decode_frame(bad)
    with pytest.raises(FrameError, match=r"^frame must be 9 bytes, got 10$"):
        decode_frame(good + b"\0")
