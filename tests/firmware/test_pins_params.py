"""Parameter edges left unpinned by the firmware mutation sample of round 22 (docs/mutation.md,
`python bench/mutation.py --layer firmware --sample 300 --seed 12`): the internal-unit ranges,
AP138 read by a command line, 138 with a wrong type, STGP of a RAM-only address and the
shape check of an EEPROM file's axis section."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.firmware.eeprom import EepromError

from .conftest import Host

INTERNAL_VMAX = 2**23 - 512   # docs/assumptions.md "Velocity parameters with AP255 = 0"
INTERNAL_AMAX = 2**16 - 1


def test_internal_unit_ranges_take_their_lowest_value():
    """TMCM-6212 4.1 AP255 = 0 "the internal units of the TMC5130 are used directly", ranges as
    docs/assumptions.md: AP4 (0 ... VMAX) takes 0 and refuses -1 with status 4, AP2 (signed)
    takes -VMAX and refuses -VMAX - 1; the tops are taken, one beyond is status 4."""
    host = Host(VirtualModule("TMCM-6212", address=1))
    host.ok(5, 255, 0, 0)
    assert [host(5, 4, 0, v).status for v in (0, -1, INTERNAL_VMAX, INTERNAL_VMAX + 1)] == [100, 4, 100, 4]
    assert [host(5, 5, 0, v).status for v in (0, -1, INTERNAL_AMAX, INTERNAL_AMAX + 1)] == [100, 4, 100, 4]
    assert [host(5, 2, 0, v).status for v in (-INTERNAL_VMAX, -INTERNAL_VMAX - 1)] == [100, 4]


def test_ap138_reads_the_same_in_ascii_as_in_binary():
    """PD86-1180 5 AP138 ramp mode "Automatically set when using ROR, ROL, MST and MVP"
    (docs/assumptions.md "AP138 read-back": ROR gives 2, MVP 0); 4.5: AGAP answers as GAP does."""
    host = Host(VirtualModule("PD86-1180", address=1))
    vm = host.vm
    host.ok(1, 0, 0, 100)                               # ROR 0, 100
    assert host.ok(6, 138) == 2
    host.ok(139)
    vm.globals.set(0, 67, 0x20)                          # no echo, only the reply
    assert vm.feed_ascii(b"AGAP 138, 0\r") == b"BA 100 2\r"
    assert vm.feed_ascii(b"AMVP ABS, 0, 0\r") == b"BA 100 0\r"
    assert vm.feed_ascii(b"AGAP 138, 0\r") == b"BA 100 0\r"


def test_138_with_a_type_beyond_1_is_status_3():
    """TMCM-6212 3.6.35: 138 type 0 "only once", 1 "always"; another type is 3.2.1 Table 4
    "3 Wrong type" with value 0, and type 1 (the last valid one) is taken."""
    host = Host(VirtualModule("TMCM-6212", address=1))
    reply = host(138, 2, 0, 1)
    assert (reply.status, reply.value) == (3, 0)
    assert host(138, 1, 0, 1).status == 100


def test_stgp_stores_the_address_given_to_the_constructor(tmp_path):
    """TMCM-6212 3.6.9 STGP: "stores a global parameter ... permanently"; VirtualModule(address=...)
    sets GP66 in RAM only (docs/assumptions.md), so STGP 66, 0 writes it: a module built from
    that EEPROM without an address answers at it."""
    ee = tmp_path / "ee.json"
    vm = VirtualModule("TMCM-6212", address=7, eeprom=ee)
    assert vm.stored_global(0, 66) is None
    Host(vm, address=7).ok(11, 66, 0)
    assert vm.stored_global(0, 66) == 7
    vm.close()
    again = VirtualModule("TMCM-6212", eeprom=ee)
    assert again.address == 7


_HEAD = '{"format":"opentmcl-eeprom","version":1,"module":"TMCM-6212"'


@pytest.mark.parametrize("axis", ['{"0":5}', '{"0":{"4":"fast"}}', '[1]'])
def test_a_damaged_axis_section_is_refused(tmp_path, axis):
    """docs/architecture.md "Errors": stored axis parameters are 32-bit integers per motor
    (PD86-1180 4.6.7 STAP "transferred to EEPROM"); an axis section of another shape or with a
    text value is a damaged file, refused as EepromError, the file keeping its bytes."""
    path = tmp_path / "ee.json"
    content = _HEAD + f',"axis":{axis}}}'
    path.write_text(content)
    with pytest.raises(EepromError, match="EEPROM file"):
        VirtualModule("TMCM-6212", eeprom=path)
    assert path.read_text() == content
