"""The wire behaviour of VirtualModule.handle: replies, status codes, addressing, special replies."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.protocol.frame import Reply, Request, checksum
from tests.protocol.test_manual_vectors import TMCM6212, hexbytes

from .conftest import Host

# Commands of the 6212's "Binary Form" examples that act in direct mode (program-flow ones included:
# they are answered too).
VECTORS = [v for v in TMCM6212 if v[1] != "RFS START"]


@pytest.mark.parametrize(("section", "mnemonic", "labels", "printed"), VECTORS, ids=[v[1] for v in VECTORS])
def test_every_6212_binary_example_is_answered_ok(section, mnemonic, labels, printed):
    """TMCM-6212 3.2 "Every time a command has been sent to a module, the module sends a reply": each
    printed "Binary Form of ..." frame gets a 9-byte reply with reply address 2, module address 1,
    status 100 and the same command number, with a correct checksum (3.2 Table 3)."""
    vm = VirtualModule("TMCM-6212")
    frame = hexbytes(printed)
    raw = vm.handle(frame)
    assert len(raw) == 9
    assert checksum(raw[:8]) == raw[8]
    reply = Reply.decode(raw)
    assert (reply.reply_address, reply.module_address, reply.status, reply.command) == (2, 1, 100, frame[1])


def test_gio_reply_example_bytes(m6212):
    """TMCM-6212 3.6.13 GIO example: with ADC channel 0 at 302, GIO 0, 1 is answered with
    02 01 64 0F 00 00 01 2E A5 ("Reply (Status=no error, Value=302)")."""
    m6212.vm.io.drive_input(1, 0, 302)
    assert m6212.vm.handle(hexbytes("01 0F 00 01 00 00 00 00 11")) == hexbytes("02 01 64 0F 00 00 01 2E A5")


def test_gap_reply_example_1180():
    """PD86-1180 4.6.6 GAP example reply "$02 $01 $64 $06 $00 $00 $02 $c7 ... position=711": after the
    actual position is set to 711, GAP 1, 0 answers exactly these eight bytes plus their checksum."""
    host = Host(VirtualModule("PD86-1180"))
    host.ok(5, 1, 0, 711)
    raw = host.raw(6, 1, 0)
    assert raw[:8] == hexbytes("02 01 64 06 00 00 02 C7")
    assert raw[8] == checksum(raw[:8])


def test_wrong_checksum_status_1(m6212):
    """TMCM-6212 3.2.1 status code 1 "Wrong checksum"."""
    frame = bytearray(Request(1, 6, 1, 0, 0).encode())
    frame[8] ^= 0x55
    reply = Reply.decode(m6212.vm.handle(bytes(frame)))
    assert reply.status == 1 and reply.command == 6


def test_wrong_type_status_3(anymod):
    """TMCM-6212 3.2.1 status 3 "Wrong type": an axis parameter number the module does not have."""
    assert anymod(5, 250, 0, 1).status == 3
    assert anymod(6, 250, 0).status == 3
    assert anymod(4, 7, 0, 0).status == 3  # MVP type 7


def test_invalid_value_status_4(m6212):
    """TMCM-6212 4.1: AP4 range 0...7999774 pps; a larger value gets status 4 "Invalid value" and the
    parameter keeps its value."""
    before = m6212.ok(6, 4, 0)
    assert m6212(5, 4, 0, 7999775).status == 4
    assert m6212.ok(6, 4, 0) == before
    assert m6212(5, 4, 6, 100).status == 4  # motor 6 does not exist on a six-axis module


def test_read_only_parameter_cannot_be_written(m6212):
    """TMCM-6212 4.1: AP3 "Actual speed" has access R only."""
    assert m6212(5, 3, 0, 100).status == 3


def test_frames_for_other_addresses_are_ignored(m6212):
    """TMCM-6212 3 (master/slave): a module only answers commands sent to its own address."""
    assert m6212.raw(6, 1, 0, address=2) == b""
    assert m6212.raw(6, 1, 0, address=1) != b""


def test_serial_address_change_and_secondary_address(m6212):
    """TMCM-6212 5.1: GP66 serial address (3.6.7 example SGP 66, 0, 3) and GP87 secondary address."""
    assert len(m6212.raw(9, 66, 0, 3)) == 9  # the reply still comes from address 1 ...
    m6212.address = 3
    assert m6212.ok(10, 66, 0) == 3
    assert m6212.raw(6, 1, 0, address=1) == b""
    m6212.ok(9, 87, 0, 9)
    assert Reply.decode(m6212.raw(6, 1, 0, address=9)).module_address == 3


def test_host_address_in_replies(m6212):
    """TMCM-6212 5.1: GP76 "Host address used in the reply telegrams"."""
    m6212.ok(9, 76, 0, 7)
    assert m6212(6, 1, 0).reply_address == 7


def test_suppress_reply_gp255(m6212):
    """TMCM-6212 5.1 GP255: "The reply in direct mode will be suppressed when this parameter is set to 1
    ... The reply will not be suppressed for GAP, GGP and GIO commands." """
    assert m6212.raw(9, 255, 0, 1) == b""
    assert m6212.raw(5, 4, 0, 1000) == b""
    assert m6212.raw(1, 0, 0, 100) == b""
    assert m6212.ok(6, 4, 0) == 1000
    assert m6212.ok(10, 255, 0) == 1
    assert m6212.ok(15, 0, 0) == 0
    assert m6212(5, 4, 0, -1).status == 4  # errors are still reported
    m6212.raw(9, 255, 0, 0)
    assert m6212(5, 4, 0, 2000).status == 100


def test_version_string_reply_136(anymod):
    """PD86-1180 4.6.39 "Special reply format of command 136": type 0 -> host address + 8-character
    version string, no checksum; type 1 -> normal reply with the binary version in the value."""
    raw = anymod.raw(136, 0)
    assert len(raw) == 9 and raw[0] == 2
    assert raw[1:].decode("ascii") == anymod.vm.profile.firmware_version
    assert anymod.ok(136, 1) == anymod.vm.profile.firmware_binary


def test_factory_defaults_137(tmp_path):
    """TMCM-6212 3.6.36 Table 13: 137 "Reset all settings in the EEPROM to their factory defaults. This
    command does not send a reply." Value must be 1234."""
    host = Host(VirtualModule("TMCM-6212", eeprom=tmp_path / "ee.json"))
    host.ok(9, 77, 0, 1)
    host.ok(9, 42, 2, 99)
    host.ok(11, 42, 2)
    assert host(137, 0, 0, 1).status == 4
    assert host.raw(137, 0, 0, 1234) == b""
    assert host.ok(10, 77, 0) == 0
    assert host.ok(10, 42, 2) == 0
    again = Host(VirtualModule("TMCM-6212", eeprom=tmp_path / "ee.json"))
    assert again.ok(10, 77, 0) == 0


def test_position_reached_event_138(m6212):
    """TMCM-6212 3.6.35: command 138 (example frame 01 8A 01 00 00 00 00 05 91) is answered at once with
    the motor bit mask, and an additional reply with status 128 follows when a motor in the mask reaches
    its target. (The manual's example text says "motors #2 and #3", but mask 5 selects motors 0 and 2.)"""
    vm = m6212.vm
    raw = vm.handle(hexbytes("01 8A 01 00 00 00 00 05 91"))
    assert raw[:8] == hexbytes("02 01 64 8A 00 00 00 05")
    m6212.ok(4, 0, 0, 1000)
    m6212.ok(4, 0, 1, 1000)   # motor 1 is not in the mask
    assert vm.drain_events() == []
    vm.advance(2.0)
    events = [Reply.decode(e) for e in vm.drain_events()]
    assert [(e.status, e.command, e.value) for e in events] == [(128, 138, 1)]
    m6212.ok(4, 0, 0, 0)      # type 1: permanent, so the next MVP reports too
    vm.advance(2.0)
    assert [Reply.decode(e).status for e in vm.drain_events()] == [128]


def test_position_reached_event_single_shot(m6212):
    """TMCM-6212 3.6.35: "With the type field set to 0, only for the next MVP command ... a position reached
    message will be generated." """
    m6212.ok(138, 0, 0, 1)
    m6212.ok(4, 0, 0, 500)
    m6212.vm.advance(2.0)
    assert len(m6212.vm.drain_events()) == 1
    m6212.ok(4, 0, 0, 0)
    m6212.vm.advance(2.0)
    assert m6212.vm.drain_events() == []


def test_garbage_lengths_are_ignored(m6212):
    """A frame that is not nine bytes long is no TMCL request (3.1): no reply, no state change."""
    for junk in (b"", b"\x01", b"\x01" * 8, b"\x01" * 10):
        assert m6212.vm.handle(junk) == b""
    assert m6212.ok(6, 1, 0) == 0


def test_position_reached_event_for_a_move_to_where_the_motor_is(m6212):
    """TMCM-6212 3.6.35: the additional reply is sent "when the motor has reached its target position" —
    also when the MVP asks for the position the motor already has."""
    m6212.ok(138, 0, 0, 1)
    m6212.ok(4, 0, 0, 0)
    m6212.vm.advance(0.001)
    assert [Reply.decode(e).value for e in m6212.vm.drain_events()] == [1]


@pytest.mark.parametrize("address", [0, 256, -1, "1", 1.0])
def test_constructor_rejects_an_address_outside_gp66(address):
    """TMCM-6212 5.1 GP66 "Serial address" range 1...255: a module address outside it (or not an
    integer) is a ValueError, not a module that answers from `address & 0xFF`."""
    with pytest.raises(ValueError, match="GP66"):
        VirtualModule("TMCM-6212", address=address)


@pytest.mark.parametrize("seconds", [float("nan"), float("inf"), -0.5])
def test_advance_rejects_non_finite_or_negative_time(seconds):
    """Issue #2 contract `vm.advance(seconds)` (docs/architecture.md "Errors"): NaN, infinity and
    negative spans are a clear ValueError, and the module's clock does not move."""
    vm = VirtualModule("TMCM-6212")
    with pytest.raises(ValueError, match="finite number"):
        vm.advance(seconds)
    assert vm.now == 0


def test_eeprom_file_that_cannot_be_created_fails_at_construction(tmp_path):
    """Issue #2: `eeprom="path"` keeps the EEPROM in that file; a path whose folder cannot be made
    (here: below a regular file) raises EepromError when the module is built, not a raw OSError
    from the first store command (TMCM-6212 3.6.9 STGP, 5.1 bank 0 auto-stored parameters)."""
    from opentmcl.firmware.eeprom import EepromError

    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(EepromError, match="cannot create"):
        VirtualModule("TMCM-6212", eeprom=blocker / "ee.json")


@pytest.mark.parametrize("content", [
    '{"format":"opentmcl-eeprom","version":1,"module":"TMCM-6212","axis":[1],"global":"x"}',
    '{"format":"opentmcl-eeprom","version":1,"module":"TMCM-6212","user":{"3":1.5}}',
    '{"format":"opentmcl-eeprom","version":1,"module":"TMCM-6212","program":[[1,2,300,0]]}',
    '{"format":"opentmcl-eeprom","version":99,"module":"TMCM-6212"}',
])
def test_a_damaged_eeprom_file_is_refused_and_left_unchanged(tmp_path, content):
    """docs/architecture.md "Errors" (never a corrupted EEPROM file): an image whose sections
    are not what the module writes (stored parameters are 32-bit integers, manual 3.6.7 STAP;
    program instructions are four bytes-and-value fields, 3.1) or of a newer format is an
    EepromError when the module is built, and the file keeps its bytes."""
    from opentmcl.firmware.eeprom import EepromError

    path = tmp_path / "ee.json"
    path.write_text(content)
    with pytest.raises(EepromError, match="EEPROM file"):
        VirtualModule("TMCM-6212", eeprom=path)
    assert path.read_text() == content


def test_eeprom_and_binary_files_get_ordinary_permissions(tmp_path):
    """Files we write atomically (EEPROM images, .bin programs) are readable like any file the
    user creates (mode from the umask), an existing file keeps its mode, and a missing folder is
    an error rather than a new folder tree."""
    import os
    import stat

    from opentmcl.atomicfile import write_atomic

    old = os.umask(0o022)
    try:
        new = tmp_path / "new.bin"
        write_atomic(new, b"x")
        kept = tmp_path / "kept.bin"
        kept.write_bytes(b"")
        kept.chmod(0o640)
        write_atomic(kept, b"y")
    finally:
        os.umask(old)
    assert stat.S_IMODE(new.stat().st_mode) == 0o666 & ~old
    assert stat.S_IMODE(kept.stat().st_mode) == 0o640 and kept.read_bytes() == b"y"
    with pytest.raises(FileNotFoundError):
        write_atomic(tmp_path / "no" / "such" / "x.bin", b"z")
    assert not (tmp_path / "no").exists()


def test_error_replies_carry_value_0_on_both_paths():
    """TMCM-6212 3.2 Table 3: a reply is reply address, module address, status, command, value;
    docs/assumptions.md "Firmware edges where the manuals are silent": an error reply's value is
    0. A frame with a wrong checksum (3.2.1 Table 4 "1 Wrong checksum") to a module at address 5
    gets status 1 from module 5 with value 0; a SAP that the pre-bound path refuses (4.1 AP4
    0...7999774: 7999775 is status 4) answers byte for byte what the general path answers to the
    same frame."""
    vm = VirtualModule("TMCM-6212", address=5)
    good = Request(5, 6, 1, 0, 0).encode()
    bad = Reply.decode(vm.handle(good[:8] + bytes(((good[8] + 1) & 0xFF,))))
    assert (bad.module_address, bad.status, bad.command, bad.value) == (5, 1, 6, 0)
    refused = Request(5, 5, 4, 0, 7999775).encode()
    general = VirtualModule("TMCM-6212", address=5).handle(refused)
    assert vm.handle(Request(5, 5, 4, 0, 7999774).encode())[2] == 100
    assert vm.is_prebound(refused)
    assert vm.handle(refused) == general
    assert Reply.decode(general).status == 4 and Reply.decode(general).value == 0


def test_138_with_a_type_beyond_1_is_status_3():
    """TMCM-6212 3.6.35: 138 type 0 "only once", 1 "always"; another type is 3.2.1 Table 4
    "3 Wrong type" with value 0, and type 1 (the last valid one) is taken."""
    host = Host(VirtualModule("TMCM-6212", address=1))
    reply = host(138, 2, 0, 1)
    assert (reply.status, reply.value) == (3, 0)
    assert host(138, 1, 0, 1).status == 100
