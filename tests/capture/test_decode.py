"""The side-channel decoder (capture/decode.py) on the manuals' frames."""
from __future__ import annotations

from opentmcl.capture.decode import HOST, MODULE, Decoder
from opentmcl.modules.profile import load_profile
from opentmcl.protocol.frame import Request
from opentmcl.protocol.opcodes import Op

# TMCM-6212 manual 3.6.8 example: GGP 66, 0 -> 01 0A 42 00 00 00 00 00 4D
GGP_66 = bytes.fromhex("010A4200000000004D")
# its reply: host 2, module 1, status 100, command 10, value 1
GGP_66_REPLY = bytes.fromhex("0201640A0000000172")


def decoder():
    prof = load_profile("TMCM-6212")
    return Decoder(lambda address: prof if address == 1 else None, gap=0.1)


def test_request_and_reply_are_paired_with_names_and_latency():
    """Manual 3.1/3.2: address, command, type, motor/bank, value, checksum; the reply's status text is
    the manual's (3.2.1: 100 "Successfully executed, no error")."""
    d = decoder()
    (req,) = d.feed(1.0, HOST, GGP_66)
    (rep,) = d.feed(1.0025, MODULE, GGP_66_REPLY)
    assert (req["mnemonic"], req["type"], req["motor"], req["parameter"]) == ("GGP", 66, 0, "serial_address")
    assert req["checksum_ok"] is True and req["raw"] == "01 0a 42 00 00 00 00 00 4d"
    assert rep["request"] == req["n"] and rep["latency"] == 0.0025 and rep["value"] == 1 and rep["checksum_ok"]
    assert rep["status_text"] == "Successfully executed, no error" and rep["parameter"] == "serial_address"


def test_frames_split_across_chunks_and_joined_in_one():
    d = decoder()
    assert d.feed(0.0, HOST, GGP_66[:4]) == []
    (a,) = d.feed(0.01, HOST, GGP_66[4:])
    recs = d.feed(0.02, HOST, GGP_66 + GGP_66)
    assert a["kind"] == "request" and [r["kind"] for r in recs] == ["request", "request"]


def test_partial_frame_after_a_silent_gap_is_garbage():
    """Manual 3.1 has no start marker: a partial frame older than the gap is dropped (as the served
    module does, server/framer.py); the decoder records it as garbage and frames the rest afresh."""
    d = decoder()
    d.feed(0.0, HOST, b"\x01\x06")
    recs = d.feed(0.2, HOST, GGP_66)
    assert [r["kind"] for r in recs] == ["garbage", "request"] and recs[0]["raw"] == "01 06"
    d.feed(0.3, HOST, b"\x01")
    assert [r["kind"] for r in d.feed(0.35, HOST, GGP_66[1:])] == ["request"]  # within the gap: joined


def test_a_reply_read_in_pieces_after_a_pause_stays_a_reply():
    """A module sends its reply whole; a pause between pieces of it at the proxy is the proxy's (a
    loaded machine descheduled it, a paced link gives one byte at a time), so module bytes that
    start a frame with a valid checksum (manual 3.2) stay that reply after any pause; when the
    frame they start has none, the bytes before the pause are garbage and the rest is framed anew."""
    d = decoder()
    (req,) = d.feed(1.0, HOST, GGP_66)
    assert d.feed(1.001, MODULE, GGP_66_REPLY[:3]) == []
    out = [r for i, b in enumerate(GGP_66_REPLY[3:]) for r in d.feed(1.5 + i / 1000, MODULE, bytes([b]))]
    assert [r["kind"] for r in out] == ["reply"] and out[0]["request"] == req["n"] and out[0]["value"] == 1
    (req,) = d.feed(2.0, HOST, GGP_66)
    d.feed(2.001, MODULE, b"\x55\x55")   # noise before a pause
    recs = d.feed(2.5, MODULE, GGP_66_REPLY)
    assert [r["kind"] for r in recs] == ["garbage", "reply"] and recs[0]["raw"] == "55 55"
    assert recs[1]["request"] == req["n"] and recs[1]["value"] == 1


def test_wrong_checksum_is_flagged():
    """Manual 3.2.1 status 1 "Wrong checksum"."""
    (rec,) = decoder().feed(0.0, HOST, GGP_66[:8] + b"\x00")
    assert rec["checksum_ok"] is False


def test_version_string_reply_has_no_checksum():
    """PD86-1180 manual 4.6.39: reply address then eight characters, "There is no checksum"."""
    d = decoder()
    d.feed(0.0, HOST, bytes.fromhex("01880000000000008A"))  # 136 type 0
    (rep,) = d.feed(0.01, MODULE, b"\x02" + b"6212V105")
    assert rep["kind"] == "version" and rep["version"] == "6212V105" and d.identity["address"] == 1


def test_event_reply_is_not_taken_for_the_reply_of_a_pending_request():
    """Manual 3.6.35: the additional reply of 138 has status 128 and the motor mask; it may arrive
    while another request waits for its reply."""
    d = decoder()
    d.feed(0.0, HOST, GGP_66)
    event = bytes.fromhex("0201808A00000001") + bytes([sum(bytes.fromhex("0201808A00000001")) & 0xFF])
    (ev,) = d.feed(0.001, MODULE, event)
    (rep,) = d.feed(0.002, MODULE, GGP_66_REPLY)
    assert ev["kind"] == "event" and ev["value"] == 1 and "request" not in ev
    assert rep["kind"] == "reply" and "request" in rep


def test_ascii_mode_after_139_until_bin():
    """PD86-1180 manual 4.5: command 139 enters ASCII mode; the BIN command returns to binary."""
    d = decoder()
    enter = bytes.fromhex("018B00000000000" + "08C")
    d.feed(0.0, HOST, enter)
    ok = bytes.fromhex("0201648B00000000") + bytes([sum(bytes.fromhex("0201648B00000000")) & 0xFF])
    d.feed(0.001, MODULE, ok)
    (line,) = d.feed(0.01, HOST, b"AGAP 1, 0\r")
    (text,) = d.feed(0.02, MODULE, b"BA 100 0\r")
    (bin_line,) = d.feed(0.03, HOST, b"ABIN\r")
    (again,) = d.feed(0.05, HOST, GGP_66)
    assert (line["kind"], line["text"], text["kind"], bin_line["text"]) == ("ascii", "AGAP 1, 0\r", "ascii", "ABIN\r")
    assert again["kind"] == "request"


def test_long_ascii_text_is_split_into_bounded_records():
    """PD28-1021 manual 3.4: text lines end with <CR>; a flood without one must not grow a record
    beyond the reader's line cap (docs/capture.md)."""
    import json

    from opentmcl.capture import MAX_LINE_BYTES
    from opentmcl.capture.decode import MAX_TEXT

    d = decoder()
    d.ascii[HOST] = d.ascii[MODULE] = True
    recs = d.feed(0.0, HOST, b"\x01" * (3 * MAX_TEXT)) + d.feed(0.0, MODULE, b"\x02" * (5 * MAX_TEXT + 1))
    assert [len(bytes.fromhex(r["raw"])) for r in recs] == [MAX_TEXT] * 3 + [MAX_TEXT] * 5 + [1]
    assert all(len(json.dumps({"record": "frame", **r})) < MAX_LINE_BYTES for r in recs)
    (line,) = d.feed(0.0, HOST, b"AGAP 1, 0\r")
    assert line["text"] == "AGAP 1, 0\r"


def test_aap_and_agp_name_the_parameter_their_type_field_numbers():
    """TMCM-6212 3.6.27 AAP "<parameter number>, <motor number>" and 3.6.28 AGP "<parameter number>,
    <bank number>" (docs/capture.md `parameter`): named as SAP 4, 0 and SGP 66, 0 are; ACO's type is
    a coordinate (3.6.25), no parameter."""
    d = decoder()
    aap, agp, aco = (d.feed(1.0, HOST, Request(1, c, t, 0, 0).encode())[0]
                     for c, t in ((Op.AAP, 4), (Op.AGP, 66), (Op.ACO, 4)))
    assert aap["parameter"] == "max_positioning_speed" and agp["parameter"] == "serial_address"
    assert "parameter" not in aco
