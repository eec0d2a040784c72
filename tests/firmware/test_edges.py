"""Range edges of the direct-mode commands: the last valid value and the first invalid one, for
every module (profiles give the sizes). TMCM-6212 3.2.1 Table 4: "3 Wrong type", "4 Invalid
value"; docs/assumptions.md ("Firmware (direct mode)"): "Status for an axis/motor or bank that does
not exist: 4 (invalid value)"."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.modules.addresses import address_error
from opentmcl.protocol.frame import Reply

from .conftest import Host

MODULES = ["TMCM-6212", "PD86-1180", "PD28-1021"]

# (command, type, value) of commands that act on one motor in direct mode (TMCM-6212 3.6.1-3.6.8,
# 3.6.11, 3.6.22-3.6.25, 3.6.28 AAP); STAP/RSAP only where the profile has them.
MOTOR_COMMANDS = [(1, 0, 0), (2, 0, 0), (3, 0, 0), (4, 0, 0), (5, 4, 1000), (6, 4, 0), (7, 4, 0),
                  (8, 4, 0), (13, 2, 0), (30, 1, 0), (31, 1, 0), (32, 1, 0), (34, 1, 0), (39, 1, 0)]


@pytest.mark.parametrize("name", MODULES)
def test_last_motor_is_accepted_and_the_next_is_status_4(name):
    """Motor numbers 0..axes-1 (TMCM-6212 3.6: "<motor number> 0...5"; PD86-1180 4.6: "0"): each
    motor command is status 100 on the last motor and status 4 one beyond it."""
    host = Host(VirtualModule(name, address=1))
    last = host.vm.profile.axes - 1
    got = {c: (host(c, t, last, v).status, host(c, t, last + 1, v).status)
           for c, t, v in MOTOR_COMMANDS if c in host.vm.profile.opcodes}
    assert got == {c: (100, 4) for c in got}
    assert len(got) >= 12


def test_138_mask_takes_the_bit_of_the_last_motor_and_refuses_the_next():
    """TMCM-6212 3.6.35: "The value field contains a bit mask where every bit stands for one motor.
    Bit 0 stands for motor #0, bit 1 stands for motor #1": bit 5 (motor #5) and all six bits are
    accepted and echoed, bit 6 (no motor #6) is status 4; the arrival of motor 5 is reported."""
    host = Host(VirtualModule("TMCM-6212", address=1))
    assert (host(138, 0, 0, 0x40).status, host(138, 0, 0, -1).status) == (4, 4)
    assert host.ok(138, 0, 0, 0x3F) == 0x3F
    assert host.ok(138, 1, 0, 0x20) == 0x20
    host.ok(4, 0, 4, 300)  # motor 4 is not in the mask
    host.ok(4, 0, 5, 300)
    host.vm.advance(2.0)
    assert [(e.status, e.value) for e in map(Reply.decode, host.vm.drain_events())] == [(128, 0x20)]


@pytest.mark.parametrize("name", MODULES)
def test_coordinate_numbers_end_at_the_profiles_last(name):
    """TMCM-6212 3.6.22: "Up to 20 position values (coordinates) can be stored for every axis"
    (numbers 0...20, coordinate 0 in RAM only): SCO, GCO, CCO and ACO take the last coordinate and
    answer status 3 (wrong type) one beyond it; MVP COORD (the coordinate in the value) status 4."""
    host = Host(VirtualModule(name, address=1))
    n = host.vm.profile.coordinates
    assert n == 20
    host.ok(30, n, 0, -1234)
    assert host.ok(31, n, 0) == -1234
    host.ok(4, 2, 0, n)  # MVP COORD to the last coordinate
    host.vm.advance(3.0)
    assert host.ok(6, 1, 0) == -1234
    got = {c: (host(c, n, 0, 7).status, host(c, n + 1, 0, 7).status) for c in (30, 31, 32, 39)}
    assert got == {30: (100, 3), 31: (100, 3), 32: (100, 3), 39: (100, 3)}
    assert (host(4, 2, 0, n + 1).status, host(4, 2, 0, -1).status) == (4, 4)


@pytest.mark.parametrize("name", MODULES)
def test_eeprom_forms_of_sco_gco_take_the_last_coordinate(name, tmp_path):
    """TMCM-6212 3.6.22/3.6.23: "SCO <coordinate number>, 255, 0" copies one coordinate to the EEPROM
    and "GCO <coordinate number>, 255, 0" back (0 = all): the last coordinate is accepted, one beyond
    it is status 3, and the value makes the round trip."""
    host = Host(VirtualModule(name, address=1, eeprom=tmp_path / "ee.json"))
    n = host.vm.profile.coordinates
    host.ok(30, n, 0, 4321)
    assert (host(30, n, 255, 0).status, host(30, n + 1, 255, 0).status) == (100, 3)
    host.ok(30, n, 0, 0)
    assert (host(31, n, 255, 0).status, host(31, n + 1, 255, 0).status) == (100, 3)
    assert host.ok(31, n, 0) == 4321


@pytest.mark.parametrize("name", MODULES)
def test_program_memory_addresses_end_at_its_size(name):
    """1 Features: the program memory holds `program_memory` commands (6144 / 2048). 132 (start
    download at address), 134 (3.6.36 "Return contents of the specified program memory location")
    and 129 type 1 ("run from address") take the last address and refuse the first one beyond it
    (and -1) with status 4."""
    host = Host(VirtualModule(name, address=1))
    last = host.vm.profile.program_memory - 1
    assert (host(132, 0, 0, last + 1).status, host(132, 0, 0, -1).status) == (4, 4)
    host.ok(132, 0, 0, last)
    assert host(1, 0, 0, 777).status == 101  # stored at the last address
    assert host(1, 0, 0, 778).status == 4  # the first that does not fit
    host.ok(133)
    assert host.raw(134, 0, 0, last)[1:8] == bytes([1, 0, 0]) + (777).to_bytes(4, "big")
    assert (host(134, 0, 0, last + 1).status, host(134, 0, 0, -1).status) == (4, 4)
    assert (host(129, 1, 0, last + 1).status, host(129, 1, 0, -1).status) == (4, 4)
    assert host(129, 1, 0, last).status == 100


@pytest.mark.parametrize("name", MODULES)
def test_the_last_address_of_a_bus_answers_and_the_next_does_not(name):
    """TMCM-6212 5.1 GP66 "Serial address" 1...255 and 3.1 (the first byte addresses the module): a
    module at 255 answers frames to 255 only; one at 1 does not answer 0; 255 is a valid bus
    address, 256 and 0 are not."""
    top, low = Host(VirtualModule(name, address=255), address=255), Host(VirtualModule(name, address=1))
    assert len(top.raw(6, 1, 0)) == 9
    assert top.raw(6, 1, 0, address=254) == b""
    assert low.raw(6, 1, 0, address=0) == b""
    assert address_error([255, 1]) is None
    assert "1..255" in address_error([256]) and "1..255" in address_error([0])


@pytest.mark.parametrize("name", MODULES)
def test_user_variables_store_up_to_the_last_storable(name):
    """TMCM-6212 5.3: "the first 56 variables can also be stored permanently in the EEPROM" of the
    256: STGP/RSGP on variable 55 are accepted, on 56 status 3 (docs/assumptions.md); variable 255
    is the last of the bank."""
    host = Host(VirtualModule(name, address=1))
    n = host.vm.profile.storable_user_variables
    assert n == 56
    got = {c: (host(c, n - 1, 2).status, host(c, n, 2).status) for c in (11, 12)}
    assert got == {11: (100, 3), 12: (100, 3)}
    host.ok(9, 255, 2, -7)
    assert host.ok(10, 255, 2) == -7


@pytest.mark.parametrize("name", MODULES)
def test_unsigned_32_bit_parameters_take_the_top_bit(name):
    """TMCM-6212 5.4 Table 20: the timer periods are "0 ... 4294967295" (PD86-1180 6.1 GP132 "0...
    4294967295"): 2147483648 (wire value -2147483648) and 4294967295 (wire -1) are accepted and read
    back with the same 32 bits; a parameter whose range ends at 2147483647 refuses -1 (status 4)."""
    host = Host(VirtualModule(name, address=1))
    unsigned = [k for k, p in host.vm.profile.global_parameters.items() if p.max == 2**32 - 1]
    assert {(3, 0), (3, 1), (3, 2)} <= set(unsigned)
    for bank, n in unsigned:
        if (bank, n) == (0, 132):
            continue  # the tick timer keeps counting (test_parameters.py)
        for wire in (-2**31, -1, 2**31 - 1):
            host.ok(9, n, bank, wire)
            assert host.ok(10, n, bank) == wire
    signed = [k for k, p in host.vm.profile.global_parameters.items() if p.max == 2**31 - 1 and p.writable]
    assert signed and {k: host(9, k[1], k[0], -1).status for k in signed} == {k: 4 for k in signed}


@pytest.mark.parametrize("name", MODULES)
def test_cle_takes_flags_0_to_5_and_refuses_6(name):
    """TMCM-6212 3.6.29 CLE: type "0 ALL - all flags ... 5 - (ESD) shutdown flag": 5 is the last
    flag (status 100), 6 is "3 Wrong type"."""
    host = Host(VirtualModule(name, address=1))
    assert (host(36, 5).status, host(36, 6).status) == (100, 3)


@pytest.mark.parametrize("name", MODULES)
def test_types_outside_the_tables_are_wrong_type(name):
    """TMCM-6212 3.2.1 "3 Wrong type": GGP of a bank-0 number the table does not list (0) and
    command 129 with a type other than 0 and 1 (3.6.36: "0 - run from current address, 1 - run
    from specified address") answer status 3, not 4."""
    host = Host(VirtualModule(name, address=1))
    assert (host(10, 0, 0).status, host(129, 2, 0, 0).status) == (3, 3)


@pytest.mark.parametrize("name", MODULES)
def test_protected_program_memory_refuses_download_and_read_with_status_4(name):
    """GP81 "TMCL code protection" 3 (protected against disassembling and overwriting): 132 and
    134 answer status 4 at the first address, as beyond the end (docs/assumptions.md)."""
    host = Host(VirtualModule(name, address=1))
    host.ok(9, 81, 0, 3)
    assert (host(132, 0, 0, 0).status, host(134, 0, 0, 0).status) == (4, 4)
