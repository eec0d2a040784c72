"""The one 9-byte frame codec behind Request, Reply and MemoryReply (TMCM-6212 manual 3.1, 3.1.1, 3.2).

Manual 3.1 Table 2 "TMCL Command Format": module address, command number, type number, motor or
bank number, "Value (MSB first!)", checksum; Table 3 "TMCL Reply Format": reply address, module
address, status, command number, value, checksum. 3.1.1: "the checksum is calculated by adding up
all bytes (including the module address byte) using 8-bit addition".
"""
from __future__ import annotations

import pytest

from opentmcl.protocol.frame import FrameError, Reply, Request, checksum_ok, decode_frame, encode_frame
from opentmcl.protocol.replies import MemoryReply

# TMCM-6212 3.6.4 "Binary Form of MVP REL, 0, -10000" and 3.6.13 GIO reply "Value=302".
MVP_REL = ((1, 4, 1, 0, -10000), bytes.fromhex("01 04 01 00 FF FF D8 F0 CC"))
GIO_REPLY = ((2, 1, 100, 15, 302), bytes.fromhex("02 01 64 0F 00 00 01 2E A5"))


@pytest.mark.parametrize(("fields", "printed"), [MVP_REL, GIO_REPLY])
def test_codec_gives_the_manuals_bytes_both_ways(fields, printed):
    """3.6.4 / 3.6.13: the printed nine bytes are the encoding of the example's fields."""
    assert encode_frame(*fields) == printed
    assert decode_frame(printed) == fields


@pytest.mark.parametrize("cls", [Request, Reply, MemoryReply])
@pytest.mark.parametrize(("fields", "printed"), [MVP_REL, GIO_REPLY])
def test_request_reply_and_memory_reply_share_the_codec(cls, fields, printed):
    """Every 9-byte frame has the same layout: four bytes, the value MSB first, the checksum."""
    assert cls(*fields).encode() == encode_frame(*fields) == printed
    assert cls.decode(printed) == cls(*decode_frame(printed))


@pytest.mark.parametrize(("value", "wire"), [
    (0x7FFF_FFFF, "7F FF FF FF"),       # last positive 32-bit value
    (-0x8000_0000, "80 00 00 00"),      # last negative one
    (0xFFFF_FFFF, "FF FF FF FF"),       # unsigned 32-bit form of -1
    (0x1_0000_0000, "00 00 00 00"),     # first value beyond 32 bits wraps
])
def test_value_is_four_bytes_msb_first(value, wire):
    """Table 2: "4 Value (MSB first!)"; a value beyond 32 bits keeps its low 32 bits."""
    frame = encode_frame(1, 5, 4, 0, value)
    assert frame[4:8] == bytes.fromhex(wire)
    assert checksum_ok(frame)


@pytest.mark.parametrize(("byte", "sent"), [(255, 0xFF), (256, 0x00), (-1, 0xFF)])
def test_each_header_byte_is_taken_modulo_256(byte, sent):
    """Each of the first four fields is "1 byte" (Table 2); 255 is the last value that fits."""
    assert encode_frame(byte, byte, byte, byte, 0)[:4] == bytes([sent]) * 4


def test_checksum_is_the_8_bit_sum_of_the_first_eight_bytes():
    """3.1.1 "8-bit addition": the sum wraps at 256; one bit off in any byte is detected."""
    frame = bytes.fromhex("01 04 01 00 FF FF D8 F0 CC")  # sum of eight bytes = 0x3CC
    assert checksum_ok(frame)
    assert not checksum_ok(frame[:8] + bytes([0xCD]))
    assert not checksum_ok(bytes([0x00]) + frame[1:])


@pytest.mark.parametrize(("cls", "what"), [(Request, "request"), (Reply, "reply"), (MemoryReply, "memory reply")])
@pytest.mark.parametrize("length", [8, 10])
def test_a_frame_is_exactly_nine_bytes(cls, what, length):
    """3.1: "it consists of nine bytes" - one byte short or long is a FrameError naming the frame."""
    data = bytes(length)
    with pytest.raises(FrameError, match=f"{what} must be 9 bytes, got {length}"):
        cls.decode(data)
    with pytest.raises(FrameError, match=f"frame must be 9 bytes, got {length}"):
        decode_frame(data)


def test_wrong_checksum_is_refused_unless_not_verified():
    """3.2.1 status 1 "Wrong checksum": decoding checks it; `verify=False` reads the fields anyway
    (the module answers such a frame itself, with status 1)."""
    bad = MVP_REL[1][:8] + b"\x00"
    with pytest.raises(FrameError, match="wrong checksum"):
        decode_frame(bad)
    assert decode_frame(bad, verify=False) == MVP_REL[0]
    assert decode_frame(bytearray(MVP_REL[1])) == decode_frame(memoryview(MVP_REL[1])) == MVP_REL[0]
