"""Range edges and error messages of the codecs (found unpinned by mutation testing,
docs/mutation.md): each edge is tested with its last valid value and the first invalid one, and
each refusal names what was wrong in one line (the CLI prints that line)."""
from __future__ import annotations

import pytest

from opentmcl.protocol import ascii, can, replies
from opentmcl.protocol.ascii import AsciiError, EchoMode
from opentmcl.protocol.frame import FrameError, Request
from opentmcl.protocol.status import Status, message


def test_ascii_address_characters_end_at_z():
    """PD28-1021 3.4.2: "The address character is A when the module address is 1, B for modules
    with address 2 and so on": 26 is Z, 27 and 0 have no character."""
    assert ascii.address_letter(26) == "Z"
    for address in (0, 27):
        with pytest.raises(AsciiError, match=rf"^address {address} has no ASCII address character \(1..26\)$"):
            ascii.address_letter(address)


@pytest.mark.parametrize(("gp67", "mode"), [
    (0x01, EchoMode.CHARACTER), (0x11, EchoMode.LINE), (0x21, EchoMode.NONE), (0x31, EchoMode.CHARACTER),
    (0x0F, EchoMode.CHARACTER), (0x1F, EchoMode.LINE), (0x2F, EchoMode.NONE),
])
def test_echo_mode_reads_only_bits_4_and_5(gp67, mode):
    """PD28-1021 3.4.4: "Bit 0 determines the startup mode"; "When bit 4 is set and bit 5 is clear
    ... the entire line will be echoed back"; "When bit 5 is set and bit 4 is clear there will be no
    echo": the other bits (0-3) do not change the echo."""
    assert ascii.echo_mode(gp67) is mode


@pytest.mark.parametrize(("text", "value"), [
    ("-2147483648", -2**31), ("4294967295", -1), ("2147483648", -2**31), ("2147483647", 2**31 - 1),
])
def test_ascii_values_take_signed_and_unsigned_32_bit(text, value):
    """The value of a command line is a 32-bit field (3.1: "Value (MSB first)"): -2147483648 is the
    lowest, 4294967295 the highest (written unsigned), and both reach the wire as the same 32 bits."""
    assert ascii.parse_command(f"ASAP 4, 0, {text}").to_request().value == value


@pytest.mark.parametrize("text", ["-2147483649", "4294967296"])
def test_ascii_values_beyond_32_bit_are_status_4(text):
    """One beyond either end of the 32-bit field: "4 Invalid value" (TMCM-6212 3.2.1)."""
    with pytest.raises(AsciiError, match=rf"^value out of 32-bit range: {text}$") as err:
        ascii.parse_command(f"ASAP 4, 0, {text}")
    assert err.value.status == Status.INVALID_VALUE


def test_ascii_refusals_name_the_operand():
    """A value that is no number, or a literal longer than the limit, is status 4 with a message
    that names the operand."""
    with pytest.raises(AsciiError, match=r"^value must be a number, got 'x'$") as err:
        ascii.parse_command("ASAP 4, 0, x")
    assert err.value.status == Status.INVALID_VALUE
    with pytest.raises(AsciiError, match=r"^value: ") as err:
        ascii.parse_command("ASAP 4, 0, " + "1" * 5000)
    assert err.value.status == Status.INVALID_VALUE


def test_bin_has_no_binary_request():
    """PD28-1021 3.4.3 BIN "quit ASCII mode" is no TMCL command: it has no binary request."""
    with pytest.raises(AsciiError, match=r"^BIN has no binary representation$"):
        ascii.parse_command("ABIN").to_request()


def test_ascii_reply_is_ascii_text_with_cr():
    """PD28-1021 3.4.3: the reply "BA 100 5000" (host address character, module address character,
    status, value) ends with <CR>."""
    assert ascii.encode_reply(2, 1, 100, -5000) == b"BA 100 -5000\r"


@pytest.mark.parametrize("can_id", [0, can.MAX_STANDARD_ID])
def test_can_ids_span_the_standard_11_bit_range(can_id):
    """A standard CAN identifier has 11 bits: 0 and 2047 are valid module/reply IDs (GP70/GP71)."""
    assert can.check_can_id(can_id) == can_id


@pytest.mark.parametrize("can_id", [-1, can.MAX_STANDARD_ID + 1])
def test_can_ids_beyond_11_bit_are_refused(can_id):
    with pytest.raises(can.CanFrameError, match=rf"^CAN ID must be 0..2047, got {can_id!r}$"):
        can.check_can_id(can_id)


def test_can_request_and_reply_objects_encode_their_payload():
    """TMCM-6212 3.1 note: "When using the CAN interface, leave out the address byte and the
    checksum byte": 7 bytes; the 8-byte form carries the checksum of the serial frame (docs)."""
    req = can.CanRequest(4, 0, 0, 1000)
    assert req.encode() == bytes([4, 0, 0, 0, 0, 0x03, 0xE8])
    serial = Request(1, 4, 0, 0, 1000).encode()
    assert can.CanRequest(4, 0, 0, 1000, long=True).encode(address=1) == serial[1:]
    assert can.CanReply(1, 100, 4, -1).encode() == bytes([1, 100, 4, 0xFF, 0xFF, 0xFF, 0xFF])


def test_can_version_reply_lengths_and_refusals():
    """PD86-1180 4.6.39: command 136 type 0 "in an eight-byte frame is answered with eight bytes";
    a short request gets the first seven characters."""
    assert can.encode_version_reply("1180V445") == b"1180V445"
    assert can.encode_version_reply("1180V445", long=False) == b"1180V44"
    assert can.decode_version_reply(b"1180V44") == "1180V44"
    with pytest.raises(can.CanFrameError, match=r"^CAN version reply must be 7 or 8 bytes, got 9$"):
        can.decode_version_reply(b"1180V4451")
    with pytest.raises(can.CanFrameError, match=r"^CAN version reply is not ASCII$"):
        can.decode_version_reply(b"\xff" * 8)
    with pytest.raises(can.CanFrameError, match=r"^version string must be ASCII, got 'é1234567'$"):
        can.encode_version_reply("é1234567")


@pytest.mark.parametrize("address", [0, 255])
def test_version_string_reply_takes_every_reply_address(address):
    """PD86-1180 4.6.39: the reply is the reply address (one byte, 0..255) and 8 characters."""
    raw = replies.encode_version_string_reply(address, "6212V105")
    assert replies.decode_version_string_reply(raw) == (address, "6212V105")


def test_version_string_reply_refusals():
    for address in (-1, 256):
        with pytest.raises(FrameError, match=rf"^reply address must be 0..255, got {address}$"):
            replies.encode_version_string_reply(address, "6212V105")
    with pytest.raises(FrameError, match=r"^version string must be ASCII, got '6212V10é'$"):
        replies.encode_version_string_reply(2, "6212V10é")
    with pytest.raises(FrameError, match=r"^version string must be 8 characters, got 7 \('6212V10'\)$"):
        replies.encode_version_string_reply(2, "6212V10")
    with pytest.raises(FrameError, match=r"^version string reply is not ASCII$"):
        replies.decode_version_string_reply(b"\x02" + b"\xff" * 8)


def test_motor_mask_bits_0_to_31():
    """TMCM-6212 3.6.35: "Bit 0 stands for motor #0, bit 1 stands for motor #1 ... and so on" in the
    32-bit value: motors 0 and 31 have a bit, -1 and 32 do not; all 32 bits set are motors 0..31."""
    assert replies.motor_mask([0, 31]) == 1 | 1 << 31
    for motor in (-1, 32):
        with pytest.raises(ValueError, match=rf"^motor number must be 0..31, got {motor}$"):
            replies.motor_mask([motor])
    assert replies.motors_in_mask(-1) == list(range(32))


def test_frame_refusals_name_the_problem():
    """3.1: a request is nine bytes with an 8-bit checksum; what is wrong is named."""
    good = Request(1, 6, 1, 0, 0).encode()
    with pytest.raises(FrameError, match=r"^request must be 9 bytes, got 8$"):
        Request.decode(good[:8])
    with pytest.raises(FrameError, match=r"^wrong checksum$"):
        Request.decode(good[:8] + bytes([good[8] ^ 1]))
    with pytest.raises(FrameError, match=r"^memory reply must be 9 bytes, got 10$"):
        replies.MemoryReply.decode(good + b"\0")
    with pytest.raises(FrameError, match=r"^wrong checksum$"):
        replies.MemoryReply.decode(good[:8] + bytes([good[8] ^ 1]))


def test_unknown_status_message():
    """TMCM-6212 3.2.1 lists the status codes; any other code is reported as unknown, with its number."""
    assert message(4) == "Invalid value"
    assert message(99) == "Unknown status 99"


def test_instruction_values_span_32_bit_and_refuse_one_beyond():
    """TMCM-6212 3.1 "Value (MSB first)", four bytes: "SAP 4, 0, -2147483648" and "... 4294967295"
    (the same 32 bits as -1) are instructions, one beyond either end is refused with a message
    that names the operand; so are a literal that is too long and a word that is no operand."""
    from opentmcl.protocol.opcodes import OperandError, parse_instruction

    assert parse_instruction("SAP 4, 0, -2147483648") == (5, 4, 0, -2**31)
    assert parse_instruction("SAP 4, 0, 4294967295") == (5, 4, 0, -1)
    for value in (-2147483649, 4294967296):
        with pytest.raises(OperandError, match=rf"^'SAP 4, 0, {value}': value out of 32-bit range: {value}$"):
            parse_instruction(f"SAP 4, 0, {value}")
    with pytest.raises(OperandError, match=r"^value operand: "):
        parse_instruction("SAP 4, 0, " + "1" * 5000)
    with pytest.raises(OperandError, match=r"^'SAP 4, 0, x': cannot read value operand 'x'$"):
        parse_instruction("SAP 4, 0, x")
