"""Rules every module profile (data/*.toml) must keep, checked over all shipped profiles.

The fixed parameter names are the contract between firmware and host library: a parameter number
that a module has must carry the same snake_case name on every module (PD86-1180 manual 5 / 6,
TMCM-6212 manual 4 / 5 use the same numbers for the same functions).
"""
from __future__ import annotations

import re

import pytest

from opentmcl.modules.profile import ModuleProfile, load_profile, module_names

FIXED_AXIS = {
    0: "target_position", 1: "actual_position", 2: "target_speed", 3: "actual_speed",
    4: "max_positioning_speed", 5: "max_acceleration", 6: "max_current", 7: "standby_current",
    8: "position_reached", 9: "home_switch", 10: "right_limit_switch", 11: "left_limit_switch",
    12: "right_limit_switch_disable", 13: "left_limit_switch_disable", 14: "swap_limit_switches",
    15: "acceleration_a1", 16: "velocity_v1", 17: "max_deceleration", 18: "deceleration_d1",
    19: "velocity_vstart", 20: "velocity_vstop", 21: "ramp_wait_time", 24: "right_limit_switch_polarity",
    25: "left_limit_switch_polarity", 26: "soft_stop_enable", 127: "relative_positioning_option",
    130: "minimum_speed", 135: "actual_acceleration", 138: "ramp_mode", 140: "microstep_resolution",
    149: "soft_stop_flag", 153: "ramp_divisor", 154: "pulse_divisor", 193: "reference_search_mode",
    194: "reference_search_speed", 195: "reference_switch_speed", 196: "end_switch_distance",
    197: "last_reference_position", 200: "boost_current", 202: "motor_full_step_resolution",
    204: "freewheeling", 206: "actual_load_value", 207: "extended_error_flags", 208: "driver_error_flags",
    209: "encoder_position", 210: "encoder_resolution", 212: "max_encoder_deviation",
    214: "power_down_delay", 255: "unit_mode",
}
FIXED_BANK0 = {
    64: "eeprom_magic", 65: "rs485_baud_rate", 66: "serial_address", 67: "ascii_mode",
    68: "serial_heartbeat", 69: "can_bit_rate", 70: "can_reply_id", 71: "can_id", 73: "eeprom_lock",
    75: "telegram_pause_time", 76: "serial_host_address", 77: "auto_start_mode", 79: "end_switch_polarity",
    80: "shutdown_pin", 81: "tmcl_code_protection", 82: "can_heartbeat", 83: "can_secondary_address",
    84: "coordinate_storage", 85: "do_not_restore_user_variables", 87: "serial_secondary_address",
    128: "tmcl_application_status", 129: "download_mode", 130: "tmcl_program_counter", 132: "tick_timer",
    133: "random_number", 255: "suppress_reply",
}
FIXED_BANK3 = {0: "timer_0_period", 1: "timer_1_period", 2: "timer_2_period"}

NAMES = ["PD86-1180", "PD28-1021", "TMCM-6212"]
SNAKE = re.compile(r"^[a-z][a-z0-9]*(_[a-z0-9]+)*$")


@pytest.fixture(params=NAMES)
def prof(request) -> ModuleProfile:
    return load_profile(request.param)


def all_params(prof: ModuleProfile):
    yield from prof.axis_parameters.values()
    yield from prof.global_parameters.values()


def test_the_three_modules_are_shipped():
    """docs/architecture.md "Capabilities": TMCM-6212, PD28-1021 and PD86-1180 are profiles."""
    assert module_names() == sorted(NAMES)


@pytest.mark.parametrize("alias,name", [("TMCM-1180", "PD86-1180"), ("TMCM-1021", "PD28-1021"),
                                        ("tmcm_1180", "PD86-1180"), ("pd28-1021", "PD28-1021")])
def test_aliases_resolve_to_the_module(alias, name):
    """PD86-1180 manual 1: the PD86-1180 is a TMCM-1180 on a motor; PD28-1021 manual cover page: a
    PD28-1021 is made up of a TMCM-1021 module. Either name selects the same profile."""
    assert load_profile(alias) is load_profile(name)


def test_axis_parameter_names_are_unique_snake_case(prof):
    """Each axis parameter is addressable by name (ModuleProfile.axis_parameter(name))."""
    names = [p.name for p in prof.axis_parameters.values()]
    assert len(names) == len(set(names))
    assert all(SNAKE.match(n) for n in names), [n for n in names if not SNAKE.match(n)]


def test_global_parameter_names_are_unique_over_all_banks(prof):
    """ModuleProfile.global_parameter(name) searches every bank, so a name may occur once only."""
    names = [p.name for p in prof.global_parameters.values()]
    assert len(names) == len(set(names))
    assert all(SNAKE.match(n) for n in names)


def test_fixed_axis_names_are_used(prof):
    """Host library and firmware address axis parameters by these fixed names."""
    wrong = {n: p.name for n, p in prof.axis_parameters.items() if n in FIXED_AXIS and p.name != FIXED_AXIS[n]}
    assert wrong == {}


def test_fixed_global_names_are_used(prof):
    """Bank 0 numbers and the three timer periods of bank 3 carry their fixed names; every other bank 3
    parameter is an interrupt's "<source>_trigger_transition" (PD86-1180 manual 6.4)."""
    for (bank, number), p in prof.global_parameters.items():
        assert p.bank == bank
        if bank == 0 and number in FIXED_BANK0:
            assert p.name == FIXED_BANK0[number]
        if bank == 3:
            if number in FIXED_BANK3:
                assert p.name == FIXED_BANK3[number]
            else:
                assert p.name.endswith("_trigger_transition"), p.name


def test_user_variables_are_not_listed_per_parameter(prof):
    """Bank 2 (user variables, PD86-1180 manual 6.3) is described by the [module] counts only."""
    assert not [k for k in prof.global_parameters if k[0] == 2]
    assert 0 < prof.storable_user_variables <= prof.user_variables


def test_every_field_is_filled(prof):
    """Every parameter carries the manual's title and a description; access uses the manual's letters."""
    for p in all_params(prof):
        assert p.title and p.description, p
        assert p.access and set(p.access) <= set("RWEA"), p
        assert "R" in p.access or "W" in p.access, p


def test_ranges_and_values_are_consistent(prof):
    """min <= max, and an enumeration lists only values inside the range."""
    for p in all_params(prof):
        assert p.min <= p.max, p
        assert all(p.min <= v <= p.max for v in p.values), p
        assert len(set(p.values)) == len(p.values), p


def test_defaults_are_valid_values(prof):
    """A factory default must be a value SAP/SGP would accept (status 4 otherwise)."""
    bad = [(p.bank, p.number, p.name, p.default) for p in all_params(prof) if not p.accepts(p.default)]
    assert bad == []


def test_firmware_version_string_and_binary_agree(prof):
    """Command 136 (PD86-1180 manual 4.6.39): type 0 returns an 8-character version string, type 1 the
    version number (high byte major, low byte minor) with the type number in the upper 16 bits."""
    s = prof.firmware_version
    assert len(s) == 8 and s.isascii()
    m = re.fullmatch(r"(\d{4})V(\d)(\d\d)", s)
    assert m, s
    module, major, minor = (int(g) for g in m.groups())
    assert prof.firmware_binary == (module << 16) | (major << 8) | minor
    assert str(module) in prof.name + "".join(prof.aliases)


def test_opcodes_are_bytes_and_ascii_mode_matches_command_139(prof):
    """Command 139 enters ASCII mode (PD86-1180 manual 4.4.2.7); modules without ASCII mode lack it."""
    assert all(1 <= op <= 255 for op in prof.opcodes)
    assert 136 in prof.opcodes
    assert (139 in prof.opcodes) == prof.ascii_mode


def test_interrupt_vectors_match_bank_3(prof):
    """PD86-1180 manual 6.4: bank 3 configures interrupts: the timer periods and the trigger transition
    of each input/switch interrupt share the interrupt's number."""
    names = [i.name for i in prof.interrupts.values()]
    assert len(names) == len(set(names))
    assert all(n.startswith("TI_") for n in names)
    assert prof.interrupts[255].name == "TI_GLOBAL"
    for bank, number in prof.global_parameters:
        if bank == 3:
            assert number in prof.interrupts, number
    for n in (0, 1, 2):
        assert prof.interrupts[n].name == f"TI_TIMER{n}"


def test_io_ports_are_well_formed(prof):
    """GIO/SIO (PD86-1180 manual 4.6.14/4.6.15): inputs are read only, outputs can be set and read."""
    assert prof.io
    for (bank, port), io in prof.io.items():
        assert (io.bank, io.port) == (bank, port)
        assert io.kind in {"digital", "analog", "output"}
        assert io.min <= io.max
        assert ("W" in io.access) == (io.kind == "output"), io
        assert "R" in io.access
