"""CAN payload <-> serial frame mapping (TMCM-6212 manual 3.1/3.2 notes, PD86-1180 4.2)."""
import pytest

from opentmcl.server import canmap

from .helpers import GGP_66, reply


def test_request_gets_address_and_checksum_back():
    """Manual 3.1: on CAN "leave out the address byte and the checksum byte"; putting them
    back into GGP 66, 0 gives the manual's 3.6.8 example frame (checksum 4D)."""
    assert canmap.request_to_frame(GGP_66[1:8], 1) == GGP_66
    assert canmap.request_to_frame(GGP_66[1:8] + b"\xee", 1) == GGP_66  # 8th byte ignored


def test_reply_drops_reply_address_and_checksum():
    """PD86-1180 4.2: "the first byte (reply address) and the last byte (checksum) are left out"."""
    assert canmap.reply_to_payload(reply(2, 1, 100, 10, 1), GGP_66[1:8]) == bytes([1, 100, 10, 0, 0, 0, 1])


def test_version_reply_long_and_short():
    """PD86-1180, command 136 type 0: 8 bytes back for an 8-byte request, else 7."""
    special = b"\x02" + b"6212V105"
    assert canmap.reply_to_payload(special, bytes([136, 0, 0, 0, 0, 0, 0, 0])) == b"6212V105"
    assert canmap.reply_to_payload(special, bytes([136, 0, 0, 0, 0, 0, 0])) == b"6212V10"


def test_bad_lengths_raise_value_error():
    with pytest.raises(ValueError):
        canmap.request_to_frame(b"\x01\x02", 1)
    with pytest.raises(ValueError):
        canmap.reply_to_payload(b"\x01")
