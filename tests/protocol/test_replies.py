"""Special replies: 136 type 0 string, 138 event, 134 memory read."""
from __future__ import annotations

import pytest

from opentmcl.protocol.frame import FrameError, Reply, checksum
from opentmcl.protocol.replies import (
    MemoryReply,
    decode_version_string_reply,
    encode_version_string_reply,
    is_version_request,
    motor_mask,
    motors_in_mask,
    target_reached_event,
)


def test_version_string_reply_has_no_checksum():
    """PD86-1180 4.6.39 "Special reply format of command 136": byte 1 host address, bytes 2..9 the
    8-character version string, "There is no checksum in this reply format!"."""
    raw = encode_version_string_reply(2, "1180V445")
    assert raw == b"\x02" + b"1180V445" and len(raw) == 9
    assert raw[8] != checksum(raw[:8])  # last byte is the 8th character, not a checksum
    assert decode_version_string_reply(raw) == (2, "1180V445")
    # docs/sources.md "Public host clients": PyTrinamic decodes reply bytes 1..8 as ASCII
    assert raw[1:9].decode("ascii") == "1180V445"
    assert is_version_request(136, 0) and not is_version_request(136, 1)


@pytest.mark.parametrize("bad", ["1180V1.30", "V1", "12345678\u00e9"[:8] + "\u00e9"])
def test_version_string_must_be_eight_ascii_characters(bad):
    with pytest.raises(FrameError):
        encode_version_string_reply(2, bad)


def test_version_string_reply_wrong_length():
    with pytest.raises(FrameError, match="9 bytes"):
        decode_version_string_reply(b"\x02abc")


def test_target_reached_event():
    """TMCM-6212 3.6.35: additional reply, status 128, command 138, value = motor bit mask."""
    ev = target_reached_event(2, 1, motor_mask([2, 3]))
    assert ev == Reply(2, 1, 128, 138, 0b1100)
    assert motors_in_mask(ev.value) == [2, 3]
    assert motors_in_mask(-1) == list(range(32))
    with pytest.raises(ValueError):
        motor_mask([32])


def test_memory_reply_round_trip():
    """134 read program memory: the stored instruction in the module-address, status, command and
    value positions of the reply (docs/assumptions.md)."""
    rep = MemoryReply(2, 4, 1, 0, -10000)
    raw = rep.encode()
    assert raw[:8] == bytes([2, 4, 1, 0, 0xFF, 0xFF, 0xD8, 0xF0]) and raw[8] == checksum(raw[:8])
    assert MemoryReply.decode(raw) == rep
    with pytest.raises(FrameError, match="checksum"):
        MemoryReply.decode(raw[:8] + b"\x00")
