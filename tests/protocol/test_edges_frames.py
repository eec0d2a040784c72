"""Edges of the frame and CAN codecs and of the instruction formatter that the full protocol
mutation run found unpinned once its timeouts were measured right (docs/mutation.md)."""
from __future__ import annotations

import pytest

from opentmcl.protocol import ascii, can
from opentmcl.protocol.ascii import AsciiError
from opentmcl.protocol.frame import FrameError, Request
from opentmcl.protocol.opcodes import format_instruction


def test_request_decodes_without_checksum_check_when_asked():
    """TMCM-6212 3.1.1: the ninth byte is the checksum; with `verify=False` a request whose
    checksum is wrong still gives its fields, by default it is refused."""
    good = Request(1, 6, 1, 0, 0).encode()
    bad = good[:8] + bytes([good[8] ^ 0xFF])
    assert Request.decode(bad, verify=False) == Request(1, 6, 1, 0, 0)
    with pytest.raises(FrameError, match=r"^wrong checksum$"):
        Request.decode(bad)


@pytest.mark.parametrize(("field", "args"), [
    ("module address", (256, 100, 6, 0)), ("status", (1, 256, 6, 0)), ("command", (1, 100, 256, 0)),
])
def test_can_reply_fields_are_bytes_and_refusals_name_them(field, args):
    """PD86-1180 4.2: the CAN reply keeps module address, status and command, one byte each: 255
    is the last valid value, 256 is refused naming the field."""
    assert can.encode_reply(*(255 if a == 256 else a for a in args))  # the last valid value
    with pytest.raises(can.CanFrameError, match=rf"^{field} must be 0..255, got 256$"):
        can.encode_reply(*args)


@pytest.mark.parametrize(("field", "args"), [("command", (256, 0, 0, 0)), ("type", (6, 256, 0, 0))])
def test_can_request_refusals_name_the_field(field, args):
    """TMCM-6212 3.1 note: a CAN request is command, type, motor/bank and value; each of the first
    three is one byte, and one beyond is refused naming it."""
    with pytest.raises(can.CanFrameError, match=rf"^{field} must be 0..255, got 256$"):
        can.encode_request(*args)


def test_long_can_request_checksum_uses_address_0_by_default():
    """The 8-byte CAN form carries the checksum of the serial frame (docs/assumptions.md, CAN):
    without an address the frame's address byte is 0; a short request ignores the address, a long
    one refuses an address that is not a byte, naming it."""
    assert can.encode_request(6, 1, 0, 0, long=True) == Request(0, 6, 1, 0, 0).encode()[1:]
    assert can.encode_request(6, 1, 0, 0, address=300) == Request(0, 6, 1, 0, 0).encode()[1:8]
    with pytest.raises(can.CanFrameError, match=r"^address must be 0..255, got 256$"):
        can.encode_request(6, 1, 0, 0, long=True, address=256)


def test_tab_after_the_command_and_the_refused_separator():
    """PD28-1021 3.4.2 "AMVP ABS, 1, 50000": the command and its parameters are separated by
    white space (a tab too); anything else right after the command is refused with the line."""
    assert ascii.parse_command("AMST\t0").to_request() == Request(1, 3, 0, 0, 0)
    with pytest.raises(AsciiError, match=r"^expected a space after MST in 'AMST,0'$"):
        ascii.parse_command("AMST,0\r")


def test_format_instruction_names_jump_targets_and_refuses_unwritable_fields():
    """TMCM-6212 3.6.17 "Mnemonic: JA <label>": a jump's value is written as its label when one is
    known, else as the number; 3.6.1 "Mnemonic: ROR <axis>, <velocity>" has no type operand, so
    an ROR with a non-zero type field cannot be written as source (None)."""
    assert format_instruction(22, 0, 0, 5, labels={5: "loop"}) == "JA loop"
    assert format_instruction(22, 0, 0, 6, labels={5: "loop"}) == "JA 6"
    assert format_instruction(21, 1, 0, 5, labels={5: "loop"}) == "JC NZ, loop"
    assert format_instruction(1, 0, 0, 0) == "ROR 0, 0"
    assert format_instruction(1, 5, 0, 0) is None
    assert format_instruction(24, 0, 0, 0) == "RSUB"  # 3.6.19 "Mnemonic: RSUB": no operand, no blank


def test_frame_bytes_wrap_modulo_256_and_value_to_32_bit():
    """TMCM-6212 3.1: four one-byte fields and a 32-bit value, "MSB first", then the checksum
    (3.1.1, the 8-bit sum): each byte field is taken modulo 256 and the value wrapped to 32 bits
    (frame.encode_frame), at both ends of every range."""
    from opentmcl.protocol.frame import checksum, encode_frame, to_int32

    assert encode_frame(256 + 1, 256 + 2, 256 + 3, 256 + 4, 2**32 + 5) == encode_frame(1, 2, 3, 4, 5)
    assert encode_frame(255, 255, 255, 255, -1)[:8] == b"\xff" * 8
    assert encode_frame(255, 255, 255, 255, -1)[8] == (8 * 255) & 0xFF
    assert encode_frame(0, 0, 0, 0, 2**31)[4:8] == b"\x80\x00\x00\x00"
    assert [to_int32(v) for v in (2**31 - 1, 2**31, 2**32 - 1, 2**32, -(2**31) - 1)] == \
        [2**31 - 1, -(2**31), -1, 0, 2**31 - 1]
    assert checksum(bytes([255, 1])) == 0 and checksum(bytes([255, 2])) == 1
