"""Axis and global parameters through SAP/GAP, SGP/GGP, STAP/RSAP, STGP/RSGP and the EEPROM."""
from __future__ import annotations

import json

import pytest

from opentmcl import VirtualModule

from .conftest import Host
from .test_program_support import Wire

INTERNAL_VMAX = 2**23 - 512   # docs/assumptions.md "Velocity parameters with AP255 = 0"
INTERNAL_AMAX = 2**16 - 1


def test_factory_defaults_readable(anymod):
    """TMCM-6212 4.1 / PD86-1180 5: every readable axis parameter answers GAP with status 100, and the
    non-live ones read their profile default on a fresh module."""
    live = {0, 1, 2, 3, 8, 135, 207} | anymod.vm.world.axis_numbers
    for num, p in anymod.vm.profile.axis_parameters.items():
        if not p.readable:
            continue
        value = anymod.ok(6, num, 0)
        if num not in live:
            assert value == p.default, p.name


def test_sap_gap_round_trip_every_writable_parameter(anymod):
    """SAP then GAP returns the written value for every writable, non-motion axis parameter (range ends)."""
    skip = {0, 1, 2, 3} | anymod.vm.world.axis_numbers  # motion and world: tested elsewhere
    for num, p in anymod.vm.profile.axis_parameters.items():
        if not (p.writable and p.readable) or num in skip or num == 255:
            continue
        for value in (p.values[-1],) if p.values else (p.min, p.max):
            anymod.ok(5, num, 0, value)
            assert anymod.ok(6, num, 0) == value, p.name


def test_sap_0_starts_a_move_sap_1_overwrites_position(m6212):
    """TMCM-6212 4.1: AP0 "The desired target position in position mode"; AP1 "The actual position of the
    motor ... Should normally only be overwritten for reference position setting"."""
    m6212.ok(5, 1, 0, 5000)
    assert m6212.ok(6, 1, 0) == 5000
    m6212.ok(5, 0, 0, 6000)
    m6212.vm.advance(1.0)
    assert m6212.ok(6, 1, 0) == 6000
    assert m6212.ok(6, 8, 0) == 1


def test_global_bank0_auto_stored_and_restored(tmp_path):
    """TMCM-6212 5.1: "The parameters with numbers between 64 and 128 are automatically stored in the
    EEPROM" — an SGP survives a restart with a file-backed EEPROM."""
    path = tmp_path / "ee.json"
    host = Host(VirtualModule("TMCM-6212", eeprom=path))
    host.ok(9, 75, 0, 15)
    host.ok(9, 132, 0, 5)  # tick timer: RAM only
    again = Host(VirtualModule("TMCM-6212", eeprom=path))
    assert again.ok(10, 75, 0) == 15
    assert json.loads(path.read_text())["format"] == "opentmcl-eeprom"


def test_user_variables_store_restore(tmp_path):
    """TMCM-6212 5.3: 256 user variables in bank 2; "the first 56 variables can also be stored permanently
    in the EEPROM. After booting, their values are automatically restored"; 3.6.9 STGP / 3.6.10 RSGP."""
    path = tmp_path / "ee.json"
    host = Host(VirtualModule("TMCM-6212", eeprom=path))
    host.ok(9, 42, 2, -123456)
    host.ok(11, 42, 2)
    host.ok(9, 42, 2, 7)
    host.ok(12, 42, 2)
    assert host.ok(10, 42, 2) == -123456
    host.ok(9, 255, 2, 77)
    assert host.ok(10, 255, 2) == 77
    assert host(11, 56, 2).status == 3       # only 0..55 can be stored
    again = Host(VirtualModule("TMCM-6212", eeprom=path))
    assert again.ok(10, 42, 2) == -123456
    assert again.ok(10, 255, 2) == 0


def test_gp85_do_not_restore_user_variables(tmp_path):
    """TMCM-6212 5.1 GP85 "Do not restore user variables ... 1 - user variables are not restored"."""
    path = tmp_path / "ee.json"
    host = Host(VirtualModule("TMCM-6212", eeprom=path))
    host.ok(9, 3, 2, 33)
    host.ok(11, 3, 2)
    host.ok(9, 85, 0, 1)
    assert Host(VirtualModule("TMCM-6212", eeprom=path)).ok(10, 3, 2) == 0


def test_stap_rsap_1180(tmp_path):
    """PD86-1180 4.6.7 STAP: "An axis parameter previously set with SAP will be stored permanent"; 4.6.8
    RSAP copies it back from the EEPROM."""
    path = tmp_path / "ee.json"
    host = Host(VirtualModule("PD86-1180", eeprom=path))
    host.ok(5, 4, 0, 1500)
    host.ok(7, 4, 0)
    host.ok(5, 4, 0, 100)
    host.ok(8, 4, 0)
    assert host.ok(6, 4, 0) == 1500
    assert Host(VirtualModule("PD86-1180", eeprom=path)).ok(6, 4, 0) == 1500


def test_eeprom_lock_gp73_status_5(m1180):
    """PD86-1180 6.1 GP73 "Write: 1234 to lock the EEPROM, 4321 to unlock it. Read: 1=EEPROM locked";
    4.6.7: "The STAP command will not have any effect when the configuration EEPROM is locked ... the error
    code 5 ... will be returned"."""
    m1180.ok(9, 73, 0, 1234)
    assert m1180.ok(10, 73, 0) == 1
    assert m1180(7, 4, 0).status == 5
    assert m1180(11, 0, 2).status == 5
    assert m1180(9, 75, 0, 3).status == 5   # bank 0 64..127 are written to the EEPROM by SGP
    m1180.ok(9, 73, 0, 4321)
    assert m1180.ok(10, 73, 0) == 0
    m1180.ok(7, 4, 0)
    assert m1180(9, 73, 0, 5).status == 4


def test_tick_timer_gp132(m6212):
    """TMCM-6212 5.1 GP132 "A 32 bit counter that gets incremented by one every millisecond. It can also be
    reset to any start value." """
    m6212.vm.advance(1.5)
    assert m6212.ok(10, 132, 0) == 1500
    m6212.ok(9, 132, 0, 10)
    m6212.vm.advance(0.25)
    assert m6212.ok(10, 132, 0) == 260


def test_random_gp133_seeded(m6212):
    """TMCM-6212 5.1 GP133 "Returns a random number. The seed value can be set by writing to this
    parameter." — equal seeds give equal sequences, values in 0...2147483647."""
    m6212.ok(9, 133, 0, 42)
    first = [m6212.ok(10, 133, 0) for _ in range(5)]
    m6212.ok(9, 133, 0, 42)
    assert [m6212.ok(10, 133, 0) for _ in range(5)] == first
    assert all(0 <= v <= 2**31 - 1 for v in first) and len(set(first)) > 1


def test_read_only_globals(m6212):
    """TMCM-6212 5.1: GP128 application status, GP129 download mode, GP130 program counter are R only."""
    for num in (128, 129, 130):
        m6212.ok(10, num, 0)
        assert m6212(9, num, 0, 1).status == 3


def test_bank3_timer_period_full_unsigned_range(m6212):
    """TMCM-6212 5.4 Table 20: timer periods 0 .. 4294967295 [ms] — the wire value -1 is 4294967295."""
    m6212.ok(9, 0, 3, -1)
    assert m6212.ok(10, 0, 3) == -1  # the reply carries the same 32 bits


@pytest.mark.parametrize("bank", [1, 4, 7])
def test_invalid_bank(m6212, bank):
    """TMCM-6212 5: banks 0, 2 and 3 are used; bank 1 "is normally not available"."""
    assert m6212(10, 0, bank).status == 4


def test_unit_mode_internal_units(m6212):
    """TMCM-6212 4.1 AP255: "0 - the internal units of the TMC5130 are used directly";
    docs/sources.md "TMC5130": v_pps = v*16 MHz/2^24. In internal units, velocity
    2^24/16e6*51200 = 53687 moves about 51200 pps."""
    m6212.ok(5, 255, 0, 0)
    m6212.ok(5, 5, 0, 60000)
    m6212.ok(1, 0, 0, 53687)
    m6212.vm.advance(2.0)
    internal = m6212.ok(6, 3, 0)
    assert abs(internal - 53687) <= 1
    m6212.ok(5, 255, 0, 1)
    assert abs(m6212.ok(6, 3, 0) - 51200) <= 1


def test_eeprom_magic_gp64_reinitialises_at_next_power_up(tmp_path):
    """PD86-1180 6.1 GP64 "Setting this parameter to a different value as $E4 will cause re-initialization
    of the axis and global parameters (to factory defaults) after the next power up"."""
    path = tmp_path / "ee.json"
    host = Host(VirtualModule("PD86-1180", eeprom=path))
    host.ok(5, 4, 0, 1500)
    host.ok(7, 4, 0)
    host.ok(9, 75, 0, 9)
    host.ok(9, 64, 0, 0xE4)
    again = Host(VirtualModule("PD86-1180", eeprom=path))
    assert (again.ok(6, 4, 0), again.ok(10, 75, 0)) == (1500, 9)
    again.ok(9, 64, 0, 0)
    assert again.ok(6, 4, 0) == 1500                     # only after the next power up
    fresh = Host(VirtualModule("PD86-1180", eeprom=path))
    default = fresh.vm.profile.axis_parameters[4].default
    assert (fresh.ok(6, 4, 0), fresh.ok(10, 75, 0), fresh.ok(10, 64, 0)) == (default, 0, 0xE4)


def test_unit_mode_switch_keeps_the_motion_and_reexpresses_the_ramp(m6212):
    """TMCM-6212 4.1 AP255 "Units of velocity and acceleration/deceleration settings: 0 - the internal
    units of the TMC5130 are used directly 1 - the units are pps"; 6.5: v_pps = v*16 MHz/2^24 and
    a_pps2 = a*(16 MHz)^2/2^41. The unit mode changes how the ramp parameters are read, not the ramp:
    after SAP 255, 0, 0 the default AP4 = 51200 pps reads as its TMC5130 value and a move runs at the
    same top speed as before."""
    m6212.ok(5, 255, 0, 0)
    vmax = m6212.ok(6, 4, 0)
    assert vmax == round(51200 * 2**24 / 16_000_000)
    assert m6212.ok(6, 5, 0) == round(51200 * 2**41 / 16_000_000**2)
    m6212.ok(4, 0, 0, 10**7)
    m6212.vm.advance(3.0)
    assert abs(m6212.ok(6, 3, 0) - vmax) <= 1           # cruising at AP4, in internal units
    m6212.ok(5, 255, 0, 1)
    assert abs(m6212.ok(6, 4, 0) - 51200) <= 1          # and back in pps
    assert abs(m6212.ok(6, 3, 0) - 51200) <= 1


def test_internal_units_bound_only_velocity_and_acceleration():
    """TMCM-6212 4.1 AP255 "Units of velocity and acceleration/deceleration settings: 0 - the internal
    units of the TMC5130 are used directly": only those parameters change their range; AP6 "Maximum
    current 0...255" keeps its own (255 accepted, 256 status 4 "Invalid value")."""
    host = Host(VirtualModule("TMCM-6212", address=1))
    host.ok(5, 255, 0, 0)
    assert (host(5, 6, 0, 255).status, host(5, 6, 0, 256).status) == (100, 4)


def test_the_eeprom_lock_holds_after_a_power_cycle(tmp_path):
    """PD86-1180 6.1 GP73 "Configuration EEPROM lock flag ... Write: 1234 to lock the EEPROM,
    4321 to unlock it. Read: 1=EEPROM locked", access RWE: the lock is kept in the EEPROM, so a
    module powered up again on the same EEPROM is still locked - 4.6.7 STAP "will not have any
    effect when the configuration EEPROM is locked ... the error code 5" - until 4321 unlocks it."""
    path = tmp_path / "ee.json"
    Wire(VirtualModule("PD86-1180", address=1, eeprom=path)).ok(9, 73, 0, 1234)
    again = Wire(VirtualModule("PD86-1180", address=1, eeprom=path))
    assert again.ok(10, 73, 0) == 1
    assert again(7, 4, 0).status == 5
    again.ok(9, 73, 0, 4321)
    third = Wire(VirtualModule("PD86-1180", address=1, eeprom=path))
    assert third.ok(10, 73, 0) == 0
    assert third(7, 4, 0).status == 100


def test_internal_unit_ranges_take_their_lowest_value():
    """TMCM-6212 4.1 AP255 = 0 "the internal units of the TMC5130 are used directly", ranges as
    docs/assumptions.md: AP4 (0 ... VMAX) takes 0 and refuses -1 with status 4, AP2 (signed)
    takes -VMAX and refuses -VMAX - 1; the tops are taken, one beyond is status 4."""
    host = Host(VirtualModule("TMCM-6212", address=1))
    host.ok(5, 255, 0, 0)
    assert [host(5, 4, 0, v).status for v in (0, -1, INTERNAL_VMAX, INTERNAL_VMAX + 1)] == [100, 4, 100, 4]
    assert [host(5, 5, 0, v).status for v in (0, -1, INTERNAL_AMAX, INTERNAL_AMAX + 1)] == [100, 4, 100, 4]
    assert [host(5, 2, 0, v).status for v in (-INTERNAL_VMAX, -INTERNAL_VMAX - 1)] == [100, 4]


def test_stored_global_reads_the_eeprom_not_the_ram(tmp_path):
    """TMCM-6212 5.1: bank-0 parameters 64..127 are "automatically stored in the EEPROM"; the tick
    timer GP132 is not: `stored_global` shows what the EEPROM holds."""
    vm = VirtualModule("TMCM-6212", address=1, eeprom=tmp_path / "ee.json")
    vm.request(9, 75, 0, 15)
    vm.request(9, 132, 0, 5)
    assert (vm.stored_global(0, 75), vm.stored_global(0, 132)) == (15, None)
