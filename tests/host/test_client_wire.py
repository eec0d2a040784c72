"""Client framing and transport-level errors, with a scripted stand-in transport
(garbage, wrong checksums and silence are what a real module cannot produce)."""
from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.host import (
    Client,
    TmclChecksumError,
    TmclError,
    TmclProtocolError,
    TmclStatusError,
    TmclTimeout,
    UnknownParameterError,
    VersionReply,
)
from opentmcl.protocol.frame import Reply, Request

from .fakes import ScriptedTransport


def reply(status=100, command=6, value=0, module=1, host=2) -> bytes:
    return Reply(host, module, status, command, value).encode()


def test_request_bytes_are_the_manuals_mvp_example():
    """TMCM-6212 manual 3.6.4: "Binary Form of MVP ABS, 0, 90000" is
    01 04 00 00 00 01 5F 90 F5 and of "MVP REL, 0, -10000" is 01 04 01 00 FF FF D8 F0 CC."""
    t = ScriptedTransport(reply(command=4), reply(command=4))
    c = Client(t)
    c.request(4, 0, 0, 90000)
    c.request(4, 1, 0, -10000)
    assert t.sent == [bytes.fromhex("01 04 00 00 00 01 5F 90 F5"), bytes.fromhex("01 04 01 00 FF FF D8 F0 CC")]


def test_reply_value_is_decoded_as_in_the_gio_example():
    """TMCM-6212 manual 3.6.13: GIO 0, 1 (01 0F 00 01 00 00 00 00 11) answered by
    02 01 64 0F 00 00 01 2E A5, "Status=no error, Value=302"."""
    t = ScriptedTransport(bytes.fromhex("02 01 64 0F 00 00 01 2E A5"))
    r = Client(t).request(15, 0, 1)
    assert t.sent == [bytes.fromhex("01 0F 00 01 00 00 00 00 11")]
    assert (r.reply_address, r.module_address, r.status, r.command, r.value) == (2, 1, 100, 15, 302)


def test_status_other_than_100_raises_with_manual_wording_and_mnemonic():
    """TMCM-6212 manual 3.2.1 Table 4: status 4 means "Invalid value"."""
    t = ScriptedTransport(reply(status=4, command=5))
    with pytest.raises(TmclStatusError) as ei:
        Client(t).request(5, 4, 0, 51200)
    err = ei.value
    assert err.status == 4 and err.request.command == 5
    assert "status 4" in str(err) and "Invalid value" in str(err) and "SAP 4, 0, 51200" in str(err)


def test_status_101_loaded_is_success():
    """TMCM-6212 manual 3.2.1: 101 "Command loaded into TMCL program EEPROM" is not an error."""
    r = Client(ScriptedTransport(reply(status=101, command=4))).request(4, 0, 0, 5)
    assert r.status == 101


def test_silence_raises_timeout_naming_the_request():
    """TMCM-6212 manual 3.2: every command gets a reply; none within the timeout is a TmclTimeout."""
    t = ScriptedTransport(b"")
    with pytest.raises(TmclTimeout, match=r"GAP 1, 0"):
        Client(t, timeout=0.5).request(6, 1, 0)
    assert t.now == pytest.approx(0.5)


def test_partial_reply_raises_timeout():
    """A reply is nine bytes (manual 3.2 Table 3); four bytes are not a reply."""
    with pytest.raises(TmclTimeout):
        Client(ScriptedTransport(reply()[:4])).request(6, 1, 0)


def test_wrong_reply_checksum_raises_protocol_error():
    """Manual 3.2: the reply checksum is the 8-bit sum of the other bytes; a wrong one is rejected."""
    bad = bytearray(reply(value=7))
    bad[8] ^= 0x55
    with pytest.raises(TmclProtocolError, match="wrong checksum"):
        Client(ScriptedTransport(bytes(bad))).request(6, 1, 0)


def test_leading_garbage_is_skipped_by_resynchronising():
    """Bytes before a valid nine-byte reply (line noise) are skipped until the checksum fits."""
    r = Client(ScriptedTransport(b"\xff\x00\x13" + reply(value=1234))).request(6, 1, 0)
    assert r.value == 1234


def test_stale_reply_after_timeout_is_discarded_before_next_request():
    """After a timeout, a late reply must not be taken for the answer to the next request: what
    arrived meanwhile is discarded, and a fence (GGP 66: no late GAP reply can be its reply) is
    read before the next request goes out (issue 34)."""
    t = ScriptedTransport(b"", reply(command=10, value=1), reply(value=99))
    c = Client(t)
    with pytest.raises(TmclTimeout):
        c.request(6, 1, 0)
    t.feed(reply(value=-1))  # the late answer to the first request
    assert c.request(6, 1, 0).value == 99
    assert t.sent[1] == Request(1, 10, 66, 0, 0).encode()


def test_a_reply_later_still_is_read_past_by_the_fence():
    """Issue 34, "a reply that arrives after its request timed out is never taken as the reply to
    a later request": the late reply of the same command arrives after the next request went out
    (while the fence waits): it is counted as a stray reply, the next request gets its own."""
    t = ScriptedTransport(b"", reply(value=-1) + reply(command=10, value=1), reply(value=99))
    c = Client(t)
    with pytest.raises(TmclTimeout):
        c.request(6, 1, 0)
    assert c.request(6, 1, 0).value == 99
    assert c.stray_replies == 1


def test_the_fence_is_a_command_no_lost_request_had():
    """The fence is the first of GGP 66, GAP 1, 136 type 1 (TMCM-6212 manual 3.6.36: binary
    version) whose command no lost request to that module had: after a lost GGP, GAP 1; when that
    fence is lost too, the next request is not sent (TmclTimeout naming both) and the next fence is
    136 type 1, which the late GGP and GAP replies cannot be."""
    late = reply(command=10, value=-1) + reply(command=6, value=-2)
    t = ScriptedTransport(b"", b"", late + reply(command=136, value=0x10), reply(command=10, value=7))
    c = Client(t)
    with pytest.raises(TmclTimeout):
        c.request(10, 66, 0)
    with pytest.raises(TmclTimeout, match=r"to GAP 1, 0 .* and GGP 66, 0 was not sent"):
        c.request(10, 66, 0)
    assert c.request(10, 66, 0).value == 7
    assert [(f[1], f[2]) for f in t.sent] == [(10, 66), (6, 1), (136, 1), (10, 66)]
    assert c.stray_replies == 2


def test_a_garbled_reply_is_a_typed_error_naming_the_request():
    """A reply with a wrong checksum (manual 3.1.1) is a TmclChecksumError (a TmclProtocolError)
    that names the request and keeps the bytes; the next request is brought back in step."""
    bad = reply(value=5)[:8] + bytes([(reply(value=5)[8] + 1) % 256])
    t = ScriptedTransport(bad, reply(command=10, value=1), reply(value=6))
    c = Client(t)
    with pytest.raises(TmclChecksumError, match=r"GAP 1, 0 from module 1") as info:
        c.request(6, 1, 0)
    assert info.value.request == Request(1, 6, 1, 0, 0) and info.value.raw == bad
    assert c.request(6, 1, 0).value == 6


def test_replies_from_other_modules_or_commands_are_skipped():
    """Replies are matched by module address and command number (manual 3.2 Table 3)."""
    t = ScriptedTransport(reply(module=3, value=1) + reply(command=5, value=2) + reply(value=3))
    c = Client(t)
    assert c.request(6, 1, 0).value == 3
    assert c.stray_replies == 2


def test_event_reply_arriving_before_the_answer_is_kept():
    """TMCM-6212 manual 3.6.35: the additional reply has status 128, command 138 and the motor mask."""
    t = ScriptedTransport(reply(status=128, command=138, value=0b100) + reply(value=5))
    c = Client(t)
    assert c.request(6, 1, 0).value == 5
    assert c.pending_events() == 0b100
    assert c.wait_position_reached(0b100, timeout=1) == 0b100
    assert c.pending_events() == 0


def test_wait_position_reached_times_out_without_event():
    """Manual 3.6.35: without the additional reply the wait ends with TmclTimeout after `timeout`."""
    t = ScriptedTransport()
    with pytest.raises(TmclTimeout, match="0x1"):
        Client(t).wait_position_reached(1, timeout=2.0)
    assert t.now >= 2.0


def test_version_string_reply_has_no_checksum():
    """PD86-1180 manual 4.6.39: command 136 type 0 answers host address + 8 characters,
    "There is no checksum in this reply format!" (example "1180V1.30" style)."""
    t = ScriptedTransport(b"\x02" + b"1180V445")
    r = Client(t).request(136, 0, 0, 0)
    assert isinstance(r, VersionReply)
    assert (r.reply_address, r.text, r.status, r.command) == (2, "1180V445", 100, 136)


def test_version_string_reply_that_is_not_text_is_a_protocol_error():
    """PD86-1180 manual 4.6.39: bytes 2..9 are the version string (characters)."""
    with pytest.raises(TmclProtocolError):
        Client(ScriptedTransport(b"\x02\x00\x01\x02\x03\x04\x05\x06\x07")).request(136, 0)


def test_version_request_answered_with_error_status_raises():
    """A module that rejects 136 answers with a normal frame carrying the status (manual 3.2.1)."""
    with pytest.raises(TmclStatusError, match="Invalid command"):
        Client(ScriptedTransport(reply(status=2, command=136))).request(136, 0)


def test_restore_factory_settings_expects_no_reply():
    """TMCM-6212 manual 3.6.36: command 137 "does not send a reply"."""
    t = ScriptedTransport()
    assert Client(t).request(137, 0, 0, 1234) is None
    assert t.sent == [bytes.fromhex("01 89 00 00 00 00 04 D2") + bytes([(0x01 + 0x89 + 0x04 + 0xD2) & 0xFF])]


def test_can_frames_leave_out_address_and_checksum_of_the_reply():
    """PD86-1180 manual 4.2: "When using CAN bus, the first byte (reply address) and the last byte
    (checksum) are left out"; the request goes without its address byte (the CAN ID is the address)."""
    t = ScriptedTransport(bytes.fromhex("01 64 06 00 00 01 2E"), frame_format="can")
    r = Client(t).request(6, 1, 0)
    assert t.sent == [bytes.fromhex("06 01 00 00 00 00 00 08")]
    assert (r.status, r.command, r.value) == (100, 6, 302)


def test_can_version_reply_is_eight_characters():
    """PD86-1180 manual 4.6.39: sent in an eight-byte CAN frame, 136 is answered with eight bytes."""
    t = ScriptedTransport(b"6212V105", frame_format="can")
    assert Client(t).request(136, 0).text == "6212V105"


@pytest.mark.parametrize("kwargs", [dict(command=256), dict(type=-1), dict(motor=300),
                                    dict(value=2**32), dict(value=-(2**31) - 1)])
def test_out_of_range_fields_are_rejected_before_sending(kwargs):
    """Manual 3.1: command, type and motor are bytes, value is 32 bits."""
    t = ScriptedTransport()
    args = dict(command=6, type=1, motor=0, value=0) | kwargs
    with pytest.raises(ValueError):
        Client(t).request(**args)
    assert t.sent == []


@given(st.binary(max_size=40), st.sampled_from([(6, 1, 0), (136, 0, 0)]))
def test_any_bytes_give_a_reply_or_a_typed_error(data, request):
    """docs/architecture.md "Errors": whatever arrives, the client returns a reply or raises a
    TmclError — never another exception, never a hang."""
    t = ScriptedTransport(data)
    try:
        r = Client(t, timeout=1.0).request(*request)
    except TmclError:
        return
    assert r.command == request[0]


def test_module_rejects_axis_numbers_outside_the_profile():
    """TMCM-6212 manual 1: six axes, numbered 0..5."""
    m = Client(ScriptedTransport()).module(profile="TMCM-6212")
    assert m[5].number == 5
    for bad in (6, -1, "0"):
        with pytest.raises(UnknownParameterError):
            m.axis(bad)


def test_can_event_reply_belongs_to_the_transports_module():
    """TMCM-6212 manual 3.2 note: with CAN the CAN ID is the reply address; the status-128 reply
    (3.6.35) on a CAN link belongs to the module the link talks to, whatever its address byte."""
    t = ScriptedTransport(frame_format="can")
    c = Client(t, address=1)
    t.feed(bytes.fromhex("07 80 8A 00 00 00 01"))  # the module speaks unprompted
    assert c.wait_position_reached(1, timeout=1) == 1


def test_memory_reply_carries_the_stored_instruction():
    """Command 134 "special reply format" (TMCM-6212 manual 3.6.36; docs/assumptions.md): the
    stored instruction's command, type, motor and value in place of address, status, command, value."""
    t = ScriptedTransport(bytes.fromhex("02 04 01 00 FF FF D8 F0") + bytes([(0x02 + 0x04 + 0x01 + 0xFF * 2 + 0xD8 + 0xF0) & 0xFF]))
    r = Client(t).request(134, 0, 0, 7)
    assert (r.command, r.type, r.motor, r.value) == (4, 1, 0, -10000)  # MVP REL, 0, -10000
