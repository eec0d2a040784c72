"""TMCL-IDE binary file format (docs/tmcl-assembler.md): 8-byte records, checksum of the first seven bytes."""
from __future__ import annotations

import pytest

from opentmcl.lang import binfile
from opentmcl.lang.binfile import BinFileError, Instruction
from opentmcl.protocol.frame import Request


def test_record_is_serial_frame_without_address():
    """docs/tmcl-assembler.md: opcode, type, motor/bank, value (signed 32-bit big-endian), checksum = sum of the
    first seven bytes - the TMCM-6212 3.6.4 MVP REL, 0, -10000 example without its address byte
    (and so with checksum CCh - 01h)."""
    rec = Instruction(4, 1, 0, -10000).encode()
    assert rec == bytes.fromhex("040100FFFFD8F0CB")
    assert rec[:7] == Request(1, 4, 1, 0, -10000).encode()[1:8]


def test_decode_checks_length_and_checksums():
    good = binfile.encode([Instruction(2, 0, 0, 51200), Instruction(28)])
    assert binfile.decode(good) == [Instruction(2, 0, 0, 51200), Instruction(28, 0, 0, 0)]
    with pytest.raises(BinFileError, match="multiple of 8"):
        binfile.decode(good[:-1])
    bad = good[:15] + bytes([good[15] ^ 1])
    with pytest.raises(BinFileError, match="record 1 .*wrong checksum"):
        binfile.decode(bad)
    assert binfile.decode(bad, verify=False)[1].command == 28


def test_binfile_checksum_error_names_the_byte_offset():
    """docs/tmcl-assembler.md "Binary file format": 8-byte records; a wrong checksum names the
    record and its byte offset (8 x record) with both checksums in hex."""
    from opentmcl.lang import binfile
    data = bytearray(binfile.encode([binfile.Instruction(3), binfile.Instruction(28)]))
    data[15] ^= 1
    with pytest.raises(binfile.BinFileError) as err:
        binfile.decode(bytes(data))
    assert str(err.value) == "record 1 (byte offset 8): wrong checksum 1Dh, expected 1Ch"


def test_binfile_of_a_partial_record_names_the_record():
    """8-byte records: 9 bytes are record 0 and one byte of record 1; 16 bytes are two records."""
    from opentmcl.lang import binfile
    assert len(binfile.decode(bytes(16))) == 2
    with pytest.raises(binfile.BinFileError) as err:
        binfile.decode(bytes(9))
    assert str(err.value) == "length 9 is not a multiple of 8 bytes (record 1 is incomplete)"


def test_field_ranges():
    with pytest.raises(BinFileError, match="type"):
        Instruction(4, 256, 0, 0).encode()


@pytest.mark.parametrize(("name", "index"), [("command", 0), ("type", 1), ("motor", 2)])
def test_byte_field_last_valid_and_first_invalid(name, index):
    """TMCM-6212 manual 3.1: "a one-byte command field, a one-byte type field, a one-byte
    motor/bank field": 0 and 255 are written as that byte of the record; 256 and -1 are refused."""
    for v in (0, 255):
        fields = [0, 0, 0, 0]
        fields[index] = v
        assert Instruction(*fields).encode()[index] == v
    for v in (256, -1):
        fields = [0, 0, 0, 0]
        fields[index] = v
        with pytest.raises(BinFileError, match=f"{name} must be 0..255, got {v}"):
            Instruction(*fields).encode()


def test_value_field_edges():
    """TMCM-6212 manual 3.1: "4 | Value (MSB first!)" - -2^31 and 2^31-1 are the signed edges."""
    assert Instruction(4, 0, 0, -(2 ** 31)).encode()[3:7] == bytes.fromhex("80000000")
    assert Instruction(4, 0, 0, 2 ** 31 - 1).encode()[3:7] == bytes.fromhex("7FFFFFFF")


def test_write_read(tmp_path):
    path = tmp_path / "p.bin"
    binfile.write(path, [Instruction(22, 0, 0, 0)])
    assert path.read_bytes() == bytes.fromhex("1600000000000016")
    assert binfile.read(path) == [Instruction(22, 0, 0, 0)]
    assert [p.name for p in tmp_path.iterdir()] == ["p.bin"]  # no temporary file left behind
