"""CAN payloads (TMCM-6212 3.1/3.2 notes, PD86-1180 4.1/4.2/4.6.39, docs/sources.md "TMCL over CAN")."""
from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.protocol import can
from opentmcl.protocol.frame import Reply, Request

from .test_manual_vectors import TMCM6212, hexbytes


@pytest.mark.parametrize("printed", [v[3] for v in TMCM6212])
def test_request_is_serial_frame_without_address_and_checksum(printed):
    """TMCM-6212 3.1 note: "When using the CAN interface, leave out the address byte and the
    checksum byte" - the 7-byte payload of every manual example."""
    raw = hexbytes(printed)
    req = Request.decode(raw)
    payload = can.encode_request(req.command, req.type, req.motor, req.value)
    assert payload == raw[1:8]
    assert can.decode_request(payload) == can.CanRequest(req.command, req.type, req.motor, req.value)


@pytest.mark.parametrize("printed", [v[3] for v in TMCM6212])
def test_pytrinamic_eight_byte_request(printed):
    """docs/sources.md "TMCL over CAN": PyTrinamic sends the 9-byte frame without its address byte
    (8 bytes, trailing checksum ignored by the module); both lengths must be accepted."""
    raw = hexbytes(printed)
    req = Request.decode(raw)
    long = can.encode_request(req.command, req.type, req.motor, req.value, long=True, address=1)
    assert long == raw[1:]
    decoded = can.decode_request(raw[1:])
    assert decoded.long and (decoded.command, decoded.type, decoded.motor, decoded.value) == (
        req.command, req.type, req.motor, req.value)
    # the trailing byte is not checked
    assert can.decode_request(raw[1:8] + b"\x00").value == req.value


def test_reply_is_serial_reply_without_reply_address_and_checksum():
    """PD86-1180 4.2: "When using CAN bus, the first byte (reply address) and the last byte
    (checksum) are left out" - the GIO reply of TMCM-6212 3.6.13."""
    serial = hexbytes("02 01 64 0F 00 00 01 2E A5")
    assert can.encode_reply(1, 100, 15, 302) == serial[1:8]
    assert can.decode_reply(serial[1:8]) == can.CanReply(1, 100, 15, 302)


def test_version_reply_lengths():
    """PD86-1180 4.6.39: send 136 in an eight-byte frame to get all eight version characters."""
    assert can.encode_version_reply("6212V105", long=True) == b"6212V105"
    assert can.encode_version_reply("6212V105", long=False) == b"6212V10"
    assert can.decode_version_reply(b"6212V105") == "6212V105"


@pytest.mark.parametrize("bad", [b"", b"\x01" * 6, b"\x01" * 9])
def test_bad_request_lengths(bad):
    with pytest.raises(can.CanFrameError, match="7 or 8 bytes"):
        can.decode_request(bad)


def test_bad_fields_and_ids():
    with pytest.raises(can.CanFrameError, match="type"):
        can.encode_request(1, 256, 0, 0)
    with pytest.raises(can.CanFrameError, match="7 bytes"):
        can.decode_reply(b"\x00" * 8)
    with pytest.raises(can.CanFrameError, match="8 characters"):
        can.encode_version_reply("short")
    with pytest.raises(can.CanFrameError, match="ASCII"):
        can.decode_version_reply(b"\xff" * 8)
    assert can.check_can_id(2047) == 2047  # TMCM-6212 global parameters 70/71: 0...2047
    with pytest.raises(can.CanFrameError):
        can.check_can_id(2048)


@given(st.integers(0, 255), st.integers(0, 255), st.integers(0, 255), st.integers(-(2**31), 2**31 - 1))
def test_request_round_trip(cmd, typ, motor, value):
    """Any request survives encode/decode in both lengths and matches the serial frame's body."""
    for long in (False, True):
        payload = can.encode_request(cmd, typ, motor, value, long=long, address=3)
        assert can.decode_request(payload) == can.CanRequest(cmd, typ, motor, value, long)
    assert can.encode_request(cmd, typ, motor, value) == Request(3, cmd, typ, motor, value).encode()[1:8]


@given(st.integers(0, 255), st.integers(0, 255), st.integers(0, 255), st.integers(-(2**31), 2**31 - 1))
def test_reply_round_trip(addr, status, cmd, value):
    payload = can.encode_reply(addr, status, cmd, value)
    assert payload == Reply(2, addr, status, cmd, value).encode()[1:8]
    assert can.decode_reply(payload) == can.CanReply(addr, status, cmd, value)
